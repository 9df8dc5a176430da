//! Physical material randomisation on a loaded [`World`]: friction, restitution and mass of
//! every object body from its material's span in the material table
//! ([`Material::ranges`]), and the damping of object joints by a configured factor.
//!
//! Each body takes the material most of its links' visuals name (the object's category
//! material when none do). One draw per object and material: the wooden carcass and wooden
//! drawers of a cabinet share a wood, its metal handles get a metal. Values are drawn from the
//! typical values (masses from the URDF inertials, damping from the URDF), never from the
//! current ones, so applying a draw twice, or to a world that already had another draw, gives
//! the same world. Robots are not changed.

use std::collections::BTreeMap;

use hearth_kinematics::JointKind;
use rand::RngExt;
use rand_pcg::Pcg64Mcg;

use super::config::PhysicsRandomization;
use super::error::RandomizeError;
use super::sampling::{Stream, stream, uniform};
use crate::assets::{Category, Material};
use crate::world::{BodyId, LoadedScene, World};

/// What [`randomize_physics`] changed.
///
/// ```
/// let r = hearth_sim::randomize::PhysicsReport::default();
/// assert_eq!(r.bodies + r.joints, 0);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PhysicsReport {
    /// Bodies whose friction, restitution or mass was set.
    pub bodies: usize,
    /// Joints whose damping was set.
    pub joints: usize,
}

/// One material's draw: friction, restitution and the density factor.
#[derive(Clone, Copy, Debug)]
struct Draw {
    friction: f64,
    restitution: f64,
    density_factor: f64,
}

fn draw(m: Material, spread: f64, rng: &mut Pcg64Mcg) -> Draw {
    let (r, p) = (m.ranges(), m.props());
    let pick = |rng: &mut Pcg64Mcg, range: [f64; 2], typical: f64| typical + spread * (uniform(rng, range) - typical);
    let friction = pick(rng, r.friction, p.friction);
    let restitution = pick(rng, r.restitution, p.restitution);
    let density = pick(rng, r.density, p.density);
    Draw {
        friction,
        restitution,
        density_factor: density / p.density,
    }
}

/// A body of an object: its typical mass and material.
struct BodyInfo {
    body: BodyId,
    mass: f64,
    material: Material,
}

/// The bodies of object `handle` with their typical masses and materials.
fn object_bodies(world: &World, handle: crate::world::ModelHandle) -> Result<Vec<BodyInfo>, RandomizeError> {
    let model = world.model(handle)?;
    let fallback = Category::from_name(model.name().rsplit_once('_').map_or(model.name(), |(b, _)| b))
        .map_or(Material::Wood, Category::material);
    let mut per_body: Vec<(BodyId, f64, BTreeMap<Material, usize>)> = Vec::new();
    for link in model.links() {
        let body = world.link_body(handle, &link.name)?;
        let k = match per_body.iter().position(|(b, _, _)| *b == body) {
            Some(k) => k,
            None => {
                per_body.push((body, 0.0, BTreeMap::new()));
                per_body.len() - 1
            }
        };
        per_body[k].1 += link.inertial.as_ref().map_or(0.0, |i| i.mass.max(0.0));
        for v in &link.visuals {
            if let Some(m) = v.material.as_deref().and_then(|n| n.parse::<Material>().ok()) {
                *per_body[k].2.entry(m).or_insert(0) += 1;
            }
        }
    }
    Ok(per_body
        .into_iter()
        .map(|(body, mass, votes)| {
            // Most visuals win; ties go to the first material in table order.
            let material = votes
                .iter()
                .fold(None::<(Material, usize)>, |best, (&m, &n)| match best {
                    Some((_, bn)) if bn >= n => best,
                    _ => Some((m, n)),
                })
                .map_or(fallback, |(m, _)| m);
            BodyInfo { body, mass, material }
        })
        .collect())
}

/// Draws friction, restitution, mass and joint damping for every object of `loaded` in
/// `world` (and, with `cfg.building`, for the building's bodies and the ground). Draws one seed
/// from `rng`; each object has its own stream keyed by its name. Does nothing when
/// `cfg.enabled` is false.
///
/// The properties live in rapier's sets, so [`World::snapshot`] captures them and
/// [`World::restore`] brings back whatever was in place when the snapshot was taken; they do
/// not enter [`World::state_hash`] ([`World::properties_hash`] covers them).
///
/// # Errors
/// [`RandomizeError::World`] when `loaded` does not belong to `world`.
///
/// ```
/// use hearth_sim::randomize::{PhysicsRandomization, randomize_physics};
/// use hearth_sim::scene::{SceneFile, SceneObject};
/// use hearth_sim::world::{World, WorldConfig};
/// use rand::SeedableRng;
/// let mut scene = SceneFile::empty("one mug");
/// scene.objects.push(SceneObject::new("mug", "mug", 0, [0.0, 0.0, 0.0]));
/// let mut world = World::new(WorldConfig::default())?;
/// let loaded = world.load_scene(&scene).unwrap();
/// let body = world.model_bodies(loaded.object("mug").unwrap())?[0];
/// let cfg = PhysicsRandomization { enabled: true, friction: true, mass: true, ..Default::default() };
/// let m0 = world.body_mass(body)?;
/// randomize_physics(&mut world, &loaded, &cfg, &mut rand_pcg::Pcg64Mcg::seed_from_u64(2)).unwrap();
/// let (lo, hi) = (2300.0 / 2400.0, 2500.0 / 2400.0); // porcelain densities
/// let ratio = world.body_mass(body)? / m0;
/// assert!(ratio >= lo - 1e-4 && ratio <= hi + 1e-4 && (ratio - 1.0).abs() > 1e-6);
/// # Ok::<(), hearth_sim::world::WorldError>(())
/// ```
pub fn randomize_physics(
    world: &mut World,
    loaded: &LoadedScene,
    cfg: &PhysicsRandomization,
    rng: &mut Pcg64Mcg,
) -> Result<PhysicsReport, RandomizeError> {
    let base: u64 = rng.random();
    let mut report = PhysicsReport::default();
    if !cfg.enabled {
        return Ok(report);
    }
    for (name, &handle) in &loaded.objects {
        let bodies = object_bodies(world, handle)?;
        let mut r = stream(base, 0, Stream::Physics, name);
        let mut draws: BTreeMap<Material, Draw> = BTreeMap::new();
        for b in &bodies {
            draws
                .entry(b.material)
                .or_insert_with(|| draw(b.material, cfg.spread, &mut r));
        }
        for b in &bodies {
            let d = draws[&b.material];
            let mut touched = false;
            if cfg.friction {
                world.set_body_friction(b.body, d.friction)?;
                touched = true;
            }
            if cfg.restitution {
                world.set_body_restitution(b.body, d.restitution)?;
                touched = true;
            }
            let dynamic = world.bodies().get(b.body.handle()).is_some_and(|rb| rb.is_dynamic());
            if cfg.mass && dynamic && b.mass > 0.0 {
                let mass = b.mass * d.density_factor;
                match world.split_mount(handle, b.body) {
                    // A split root shares its mass with its mount, half each.
                    Some(mount) => {
                        world.set_body_mass(b.body, mass / 2.0)?;
                        world.set_body_mass(mount, mass / 2.0)?;
                    }
                    None => world.set_body_mass(b.body, mass)?,
                }
                touched = true;
            }
            report.bodies += usize::from(touched);
        }
        let joints: Vec<(String, f64)> = world
            .model(handle)?
            .joints()
            .iter()
            .filter(|j| j.kind != JointKind::Fixed)
            .map(|j| (j.name.clone(), j.dynamics.map_or(0.0, |d| d.damping.max(0.0))))
            .collect();
        let mut rj = stream(base, 1, Stream::Physics, name);
        for (joint, typical) in joints {
            let factor = uniform(&mut rj, cfg.joint_damping);
            if cfg.joint_damping != [1.0, 1.0] {
                world.set_joint_damping(handle, &joint, typical * factor)?;
                report.joints += 1;
            }
        }
    }
    if cfg.building {
        report.bodies += randomize_building(world, loaded, cfg, base)?;
    }
    Ok(report)
}

/// Friction and restitution of the building's bodies and the ground, one draw per material.
fn randomize_building(
    world: &mut World,
    loaded: &LoadedScene,
    cfg: &PhysicsRandomization,
    base: u64,
) -> Result<usize, RandomizeError> {
    let mut draws: BTreeMap<Material, Draw> = BTreeMap::new();
    let mut get = |m: Material| {
        *draws.entry(m).or_insert_with(|| {
            draw(
                m,
                cfg.spread,
                &mut stream(base, 0, Stream::Physics, &format!("building|{m}")),
            )
        })
    };
    let mut targets: Vec<(BodyId, Material)> = loaded
        .building
        .iter()
        .filter_map(|&b| world.body_material(b).map(|m| (b, m)))
        .collect();
    if let Some(ground) = world.ground() {
        // The ground carries the floors that lie on it: it takes their most common material.
        let mut votes: BTreeMap<Material, usize> = BTreeMap::new();
        for v in world.static_visuals() {
            if v.name.contains("floor/") {
                *votes.entry(v.material).or_insert(0) += 1;
            }
        }
        if let Some((&m, _)) = votes.iter().max_by_key(|&(_, n)| *n) {
            targets.push((ground, m));
        }
    }
    let mut n = 0;
    for (body, m) in targets {
        let d = get(m);
        if cfg.friction {
            world.set_body_friction(body, d.friction)?;
        }
        if cfg.restitution {
            world.set_body_restitution(body, d.restitution)?;
        }
        n += usize::from(cfg.friction || cfg.restitution);
    }
    Ok(n)
}
