//! Object randomisation: every eligible object of a [`SceneFile`] becomes another shape
//! variant of its category, uniformly scaled into the bounding box the original took.
//!
//! What is kept: names, categories, rooms, supports (`on`), yaw, `fixed`, material overrides
//! and the number of objects. The new model's box lies inside the original's (one axis
//! touching it): its bottom stays on the floor or its support, its back stays against the
//! wall for objects placed against walls (and wall-mounted ones), and it is centred on the
//! original's footprint otherwise. Initial joint positions are kept for joints the new
//! variant has (clamped to its limits) and dropped for others.
//!
//! Objects resting on a swapped support are moved onto the new support's matching surface
//! (the shelf at the most similar relative height that is large and tall enough): at the same
//! relative place on it, else at the same distance from its corner, else packed in rows in
//! their old order; the support's candidate variants are tried in turn until one takes its
//! whole load without squeezing objects together. When none does, or the result would not
//! validate, the support keeps its original model and its load is swapped in place; failing
//! that, the support and everything on it go back to the original, so the returned scene
//! always validates.

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use rand::RngExt;
use rand_pcg::Pcg64Mcg;

use super::config::ObjectRandomization;
use super::error::RandomizeError;
use super::sampling::{Stream, stream};
use crate::assets::{Asset, AssetSpec, Category, Material, Placement};
use crate::scene::{BoundingBox, OVERLAP_TOLERANCE, SceneError, SceneFile, SceneObject};

/// One object that became another variant.
///
/// ```
/// let s = hearth_sim::randomize::ObjectSwap { name: "chair_0".into(), category: hearth_sim::assets::Category::Chair, from_variant: 0, to_variant: 2, from_scale: 1.0, to_scale: 0.9 };
/// assert_ne!(s.from_variant, s.to_variant);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectSwap {
    /// Object name.
    pub name: String,
    /// Its category.
    pub category: Category,
    /// Variant before.
    pub from_variant: usize,
    /// Variant after.
    pub to_variant: usize,
    /// Scale before.
    pub from_scale: f64,
    /// Scale after.
    pub to_scale: f64,
}

/// What [`randomize_objects`] did.
///
/// ```
/// let r = hearth_sim::randomize::ObjectReport::default();
/// assert!(r.swapped.is_empty() && r.reseated.is_empty() && r.reverted.is_empty());
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectReport {
    /// Objects swapped, in scene order.
    pub swapped: Vec<ObjectSwap>,
    /// Objects moved onto the surface of their swapped support.
    pub reseated: Vec<String>,
    /// Objects put back to the original because their group would not validate.
    pub reverted: Vec<String>,
}

type AssetKey = (Category, usize, u64, Option<Material>);

#[derive(Default)]
struct Cache(HashMap<AssetKey, Asset>);

impl Cache {
    fn get(&mut self, spec: &AssetSpec) -> Option<&Asset> {
        let key = (spec.category, spec.variant, spec.scale.to_bits(), spec.material);
        let asset: &Asset = match self.0.entry(key) {
            Entry::Occupied(e) => e.into_mut(),
            // A failed build returns before anything is inserted.
            Entry::Vacant(e) => e.insert(Asset::build_spec(spec).ok()?),
        };
        Some(asset)
    }
}

/// Whether `c` may be swapped under `cfg`.
fn eligible(c: Category, cfg: &ObjectRandomization) -> bool {
    c.placement() != Placement::InWall && (cfg.categories.is_empty() || cfg.categories.iter().any(|n| n == c.name()))
}

/// The variants object `o` (of category `c`, built as `old`) may become, in a random order:
/// each spec with the offset of its frame in the original object frame.
fn candidates(
    o: &SceneObject,
    c: Category,
    old: &Asset,
    cfg: &ObjectRandomization,
    rng: &mut Pcg64Mcg,
    cache: &mut Cache,
) -> Vec<(AssetSpec, Vector3<f64>)> {
    let mut out = Vec::new();
    let mut candidates: Vec<usize> = (0..c.variants()).filter(|&v| v != o.variant).collect();
    // Fisher–Yates with the object's own stream.
    for i in (1..candidates.len()).rev() {
        let j = rng.random_range(0..=i);
        candidates.swap(i, j);
    }
    let ext_old = old.aabb_max - old.aabb_min;
    let vol_old = ext_old.x * ext_old.y * ext_old.z;
    for v in candidates {
        let Some(unit) = cache.get(&AssetSpec {
            category: c,
            variant: v,
            scale: 1.0,
            material: o.material,
        }) else {
            continue;
        };
        let ext1 = unit.aabb_max - unit.aabb_min;
        let mut k = f64::INFINITY;
        for a in 0..3 {
            if ext1[a] > 1e-9 {
                k = k.min(ext_old[a] / ext1[a]);
            }
        }
        // A hair smaller, so rounding never pushes the new box outside the old one.
        let k = k * (1.0 - 1e-9);
        if !(k.is_finite() && k > 0.1 && k <= 10.0) {
            continue;
        }
        let spec = AssetSpec {
            category: c,
            variant: v,
            scale: k,
            material: o.material,
        };
        let Some(new) = cache.get(&spec) else { continue };
        let ext_new = new.aabb_max - new.aabb_min;
        if vol_old > 0.0 && ext_new.x * ext_new.y * ext_new.z / vol_old < cfg.min_fill {
            continue;
        }
        let centre = |a: &Asset| (a.aabb_min + a.aabb_max) / 2.0;
        let back = matches!(c.placement(), Placement::AgainstWall | Placement::WallMounted { .. });
        let offset = Vector3::new(
            if back {
                old.aabb_min.x - new.aabb_min.x
            } else {
                centre(old).x - centre(new).x
            },
            centre(old).y - centre(new).y,
            old.aabb_min.z - new.aabb_min.z,
        );
        out.push((spec, offset));
    }
    out
}

/// The object with a new spec, its frame moved by `offset` (in its own frame).
fn swapped_object(o: &SceneObject, spec: &AssetSpec, offset: &Vector3<f64>, new: &Asset) -> SceneObject {
    let mut n = o.clone();
    n.variant = spec.variant;
    n.scale = spec.scale;
    let p = o.pose() * Point3::from(*offset);
    n.position = [p.x, p.y, p.z];
    if n.bbox.is_some() {
        n.bbox = Some(BoundingBox {
            min: new.aabb_min.into(),
            max: new.aabb_max.into(),
        });
    }
    let model = &new.model;
    n.joints = o
        .joints
        .iter()
        .filter_map(|(j, &x)| {
            let k = model.variable_names().iter().position(|m| m == j)?;
            Some((j.clone(), x.clamp(model.lower()[k], model.upper()[k])))
        })
        .collect();
    n
}

/// Box `[lo, hi]` of an object placed at `pose`, in the frame `frame` (axis-aligned there).
fn box_in(
    frame: &Isometry3<f64>,
    pose: &Isometry3<f64>,
    lo: &Vector3<f64>,
    hi: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let to = frame.inverse() * pose;
    let mut a = Vector3::repeat(f64::INFINITY);
    let mut b = Vector3::repeat(f64::NEG_INFINITY);
    for k in 0..8 {
        let c = Vector3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let p = to * Point3::from(c);
        a = a.inf(&p.coords);
        b = b.sup(&p.coords);
    }
    (a, b)
}

/// Where a dependent sits on its old support and which surface of the new support takes it.
struct Located {
    /// Index of the new support's surface.
    surface: usize,
    /// Index of the old support's surface.
    old_surface: usize,
    /// Box centre in the old support frame.
    c_old: Vector3<f64>,
    /// Half extents of the box in the support frame.
    half: Vector3<f64>,
    /// Box corners in the new support frame before moving.
    bl_n: Vector3<f64>,
    bh_n: Vector3<f64>,
}

/// How dependents are laid out on the new surfaces.
#[derive(Clone, Copy)]
enum Layout {
    /// At the same relative place on the surface.
    Relative,
    /// At the same distance from the surface's corner.
    Offset,
    /// Packed in rows from the surface's corner, in their old order.
    Packed,
}

/// Gap between objects packed onto a surface, metres.
const PACK_GAP: f64 = 0.02;

/// Finds where dependent `d` (built as `d_asset`) rests on the old support (`s_old` at
/// `s_old_pose`) and the surface of the new one (`s_new` at `s_new_pose`) that takes it: the
/// one at the most similar relative height that is large and tall enough. `None` when none is.
fn locate(
    d: &SceneObject,
    d_asset: &Asset,
    s_old_pose: &Isometry3<f64>,
    s_old: &Asset,
    s_new_pose: &Isometry3<f64>,
    s_new: &Asset,
) -> Option<Located> {
    let pose = d.pose();
    let (bl, bh) = box_in(s_old_pose, &pose, &d_asset.aabb_min, &d_asset.aabb_max);
    let c = (bl + bh) / 2.0;
    let half = (bh - bl) / 2.0;
    let (old_surface, old) = s_old
        .surfaces
        .iter()
        .enumerate()
        .filter(|(_, s)| {
            (s.z - bl.z).abs() < 0.03
                && c.x > s.min[0] - 0.02
                && c.x < s.max[0] + 0.02
                && c.y > s.min[1] - 0.02
                && c.y < s.max[1] + 0.02
        })
        .min_by(|(_, a), (_, b)| (a.z - bl.z).abs().total_cmp(&(b.z - bl.z).abs()))?;
    let height = |a: &Asset| (a.aabb_max.z - a.aabb_min.z).max(1e-9);
    let rel_old = old.z / height(s_old);
    let (surface, _) = s_new
        .surfaces
        .iter()
        .enumerate()
        .filter(|(_, s)| {
            2.0 * half.x <= s.max[0] - s.min[0] && 2.0 * half.y <= s.max[1] - s.min[1] && 2.0 * half.z <= s.clearance
        })
        .min_by(|(_, a), (_, b)| {
            let ra = (a.z / height(s_new) - rel_old).abs();
            let rb = (b.z / height(s_new) - rel_old).abs();
            ra.total_cmp(&rb)
        })?;
    let (bl_n, bh_n) = box_in(s_new_pose, &pose, &d_asset.aabb_min, &d_asset.aabb_max);
    Some(Located {
        surface,
        old_surface,
        c_old: c,
        half,
        bl_n,
        bh_n,
    })
}

/// Box centres (new support frame, x and y) for every located dependent under `layout`;
/// `None` when packing runs out of room.
fn lay_out(located: &[Located], s_old: &Asset, s_new: &Asset, layout: Layout) -> Option<Vec<[f64; 2]>> {
    let mut targets = vec![[0.0; 2]; located.len()];
    match layout {
        Layout::Relative | Layout::Offset => {
            for (l, t) in located.iter().zip(&mut targets) {
                let (old, new) = (&s_old.surfaces[l.old_surface], &s_new.surfaces[l.surface]);
                #[allow(clippy::needless_range_loop, reason = "`a` indexes six per-axis arrays")]
                for a in 0..2 {
                    let x = match layout {
                        Layout::Offset => new.min[a] + (l.c_old[a] - old.min[a]),
                        _ => {
                            let u = ((l.c_old[a] - old.min[a]) / (old.max[a] - old.min[a]).max(1e-9)).clamp(0.0, 1.0);
                            new.min[a] + u * (new.max[a] - new.min[a])
                        }
                    };
                    let (lo, hi) = (new.min[a] + l.half[a], new.max[a] - l.half[a]);
                    t[a] = if lo <= hi { x.clamp(lo, hi) } else { (lo + hi) / 2.0 };
                }
            }
        }
        Layout::Packed => {
            for (k, surf) in s_new.surfaces.iter().enumerate() {
                let mut items: Vec<usize> = (0..located.len()).filter(|&i| located[i].surface == k).collect();
                items.sort_by(|&a, &b| {
                    let (la, lb) = (&located[a], &located[b]);
                    let za = s_old.surfaces[la.old_surface].z;
                    let zb = s_old.surfaces[lb.old_surface].z;
                    za.total_cmp(&zb)
                        .then(la.c_old.x.total_cmp(&lb.c_old.x))
                        .then(la.c_old.y.total_cmp(&lb.c_old.y))
                });
                let (mut x, mut y, mut depth) = (surf.min[0], surf.min[1], 0.0_f64);
                for i in items {
                    let (dx, dy) = (2.0 * located[i].half.x, 2.0 * located[i].half.y);
                    if y + dy > surf.max[1] + 1e-9 {
                        x += depth + PACK_GAP;
                        y = surf.min[1];
                        depth = 0.0;
                    }
                    if x + dx > surf.max[0] + 1e-9 || y + dy > surf.max[1] + 1e-9 {
                        return None;
                    }
                    targets[i] = [x + dx / 2.0, y + dy / 2.0];
                    y += dy + PACK_GAP;
                    depth = depth.max(dx);
                }
            }
        }
    }
    Some(targets)
}

/// Moves a located dependent to box centre `target` on its new surface: its position, and its
/// box in the new support frame.
fn put(
    d: &SceneObject,
    l: &Located,
    target: [f64; 2],
    s_new_pose: &Isometry3<f64>,
    s_new: &Asset,
) -> ([f64; 3], Vector3<f64>, Vector3<f64>) {
    let c_n = (l.bl_n + l.bh_n) / 2.0;
    let delta = Vector3::new(
        target[0] - c_n.x,
        target[1] - c_n.y,
        s_new.surfaces[l.surface].z - l.bl_n.z,
    );
    let moved = Translation3::from(s_new_pose.rotation * delta) * d.pose();
    let t = moved.translation.vector;
    ([t.x, t.y, t.z], l.bl_n + delta, l.bh_n + delta)
}

/// A moved dependent: its index, then what [`put`] gives (its position, and its box `lo`, `hi`
/// in the new support frame).
type Move = (usize, ([f64; 3], Vector3<f64>, Vector3<f64>));

/// Whether two of the moved objects' boxes (support frame) interpenetrate by more than the
/// scene format's tolerance.
fn crowded(moves: &[Move]) -> bool {
    for (i, (_, (_, lo_a, hi_a))) in moves.iter().enumerate() {
        for (_, (_, lo_b, hi_b)) in &moves[i + 1..] {
            let depth = (0..3)
                .map(|k| hi_a[k].min(hi_b[k]) - lo_a[k].max(lo_b[k]))
                .fold(f64::INFINITY, f64::min);
            if depth > OVERLAP_TOLERANCE {
                return true;
            }
        }
    }
    false
}

/// The root of an object's support chain (itself when it rests on nothing).
fn root_of(i: usize, scene: &SceneFile, index: &HashMap<&str, usize>) -> usize {
    let mut r = i;
    for _ in 0..scene.objects.len() {
        match scene.objects[r].on.as_deref().and_then(|s| index.get(s)) {
            Some(&s) if s != r => r = s,
            _ => break,
        }
    }
    r
}

/// Swaps objects of `scene` for other variants of their categories (see the [module
/// docs](crate::randomize)). Draws one seed from `rng`; each object then has its own stream
/// keyed by its name, so whether an object is swapped, and for what, does not depend on the
/// others.
///
/// # Errors
/// [`RandomizeError::Scene`] when the input scene does not validate (the scene is unchanged).
///
/// ```
/// use hearth_sim::randomize::{ObjectRandomization, randomize_objects};
/// use hearth_sim::scene::{SceneFile, SceneObject};
/// use rand::SeedableRng;
/// let mut scene = SceneFile::empty("dining");
/// scene.objects.push(SceneObject::new("table", "table", 0, [0.0, 0.0, 0.0]));
/// let cfg = ObjectRandomization { enabled: true, ..Default::default() };
/// let report = randomize_objects(&mut scene, &cfg, &mut rand_pcg::Pcg64Mcg::seed_from_u64(1)).unwrap();
/// assert_eq!(report.swapped.len(), 1);
/// assert_ne!(scene.objects[0].variant, 0);
/// assert!(scene.validate().is_ok());
/// ```
pub fn randomize_objects(
    scene: &mut SceneFile,
    cfg: &ObjectRandomization,
    rng: &mut Pcg64Mcg,
) -> Result<ObjectReport, RandomizeError> {
    let base: u64 = rng.random();
    let assets = scene.assets()?;
    let mut report = ObjectReport::default();
    if !cfg.enabled {
        return Ok(report);
    }
    let original = scene.objects.clone();
    let n = original.len();
    let index: HashMap<&str, usize> = original.iter().enumerate().map(|(i, o)| (o.name.as_str(), i)).collect();
    let mut cache = Cache::default();

    // 1. Each object's own swap.
    let mut new_assets: Vec<Asset> = assets.clone();
    let mut objects = original.clone();
    let mut swapped = vec![false; n];
    let mut options: Vec<Vec<(AssetSpec, Vector3<f64>)>> = vec![Vec::new(); n];
    for (i, o) in original.iter().enumerate() {
        let Some(c) = Category::from_name(&o.category) else {
            continue;
        };
        if !eligible(c, cfg) {
            continue;
        }
        let mut r = stream(base, 0, Stream::Objects, &o.name);
        if r.random::<f64>() >= cfg.probability {
            continue;
        }
        options[i] = candidates(o, c, &assets[i], cfg, &mut r, &mut cache);
        let Some((spec, offset)) = options[i].first() else {
            continue;
        };
        let Some(new) = cache.get(spec) else { continue };
        objects[i] = swapped_object(o, spec, offset, new);
        new_assets[i] = new.clone();
        swapped[i] = true;
    }

    // 2. Dependents of swapped supports move onto the new surfaces (supports first).
    let depth = |i: usize| {
        let mut d = 0;
        let mut r = i;
        while let Some(&s) = original[r].on.as_deref().and_then(|s| index.get(s)) {
            if s == r || d > n {
                break;
            }
            d += 1;
            r = s;
        }
        d
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&i| depth(i));
    let roots: Vec<usize> = (0..n).map(|i| root_of(i, scene, &index)).collect();
    let own = objects.clone();
    // Group levels, indexed by root: 0 = swapped supports with their load moved onto them,
    // 1 = supports as they were with their load swapped in place, 2 = all as they were.
    let mut level = vec![0u8; n];
    let dependents: Vec<Vec<usize>> = (0..n)
        .map(|s| {
            (0..n)
                .filter(|&d| original[d].on.as_deref() == Some(original[s].name.as_str()) && d != s)
                .collect()
        })
        .collect();
    for &s in &order {
        if !swapped[s] || dependents[s].is_empty() {
            continue;
        }
        // The first variant (in the object's own random order) whose surfaces take the whole
        // load without squeezing it together.
        let mut placed = None;
        'variants: for (spec, offset) in &options[s] {
            let Some(new) = cache.get(spec) else { continue };
            let support = swapped_object(&original[s], spec, offset, new);
            let (s_old_pose, s_new_pose) = (original[s].pose(), support.pose());
            let located: Option<Vec<Located>> = dependents[s]
                .iter()
                .map(|&d| locate(&objects[d], &new_assets[d], &s_old_pose, &assets[s], &s_new_pose, new))
                .collect();
            let Some(located) = located else { continue };
            for layout in [Layout::Relative, Layout::Offset, Layout::Packed] {
                let Some(targets) = lay_out(&located, &assets[s], new, layout) else {
                    continue;
                };
                let moves: Vec<_> = dependents[s]
                    .iter()
                    .zip(&located)
                    .zip(targets)
                    .map(|((&d, l), t)| (d, put(&objects[d], l, t, &s_new_pose, new)))
                    .collect();
                if !crowded(&moves) {
                    placed = Some((support, new.clone(), moves));
                    break 'variants;
                }
            }
        }
        match placed {
            Some((support, new, moves)) => {
                objects[s] = support;
                new_assets[s] = new;
                for (d, (p, _, _)) in moves {
                    objects[d].position = p;
                }
            }
            None => level[roots[s]] = 1,
        }
    }
    let full = objects;
    let is_support: Vec<bool> = original
        .iter()
        .map(|o| original.iter().any(|d| d.on.as_deref() == Some(o.name.as_str())))
        .collect();
    let compose = |level: &[u8]| -> Vec<SceneObject> {
        (0..n)
            .map(|k| match level[roots[k]] {
                0 => full[k].clone(),
                1 if !is_support[k] => own[k].clone(),
                _ => original[k].clone(),
            })
            .collect()
    };

    // 3. Step groups back until the scene validates.
    let mut candidate = scene.clone();
    for _ in 0..=2 * n {
        candidate.objects = compose(&level);
        let names: Vec<String> = match candidate.validate() {
            Ok(()) => break,
            Err(SceneError::Overlap { a, b, .. }) => vec![a, b],
            Err(SceneError::WallOverlap { object, .. }) => vec![object],
            Err(e) => return Err(e.into()),
        };
        let mut groups: Vec<usize> = names
            .iter()
            .filter_map(|m| index.get(m.as_str()))
            .map(|&k| roots[k])
            .collect();
        groups.dedup();
        let mut any = false;
        for r in groups {
            if level[r] < 2 {
                level[r] += 1;
                any = true;
            }
        }
        if !any {
            // Only changed objects can have made the scene invalid; stop looking.
            break;
        }
    }
    candidate.objects = compose(&level);
    candidate.validate()?;
    let reverted: Vec<bool> = (0..n)
        .map(|k| swapped[k] && candidate.objects[k] == original[k])
        .collect();
    let reseated: Vec<bool> = (0..n)
        .map(|k| candidate.objects[k].position != own[k].position && candidate.objects[k] != original[k])
        .collect();

    for i in 0..n {
        if reverted[i] {
            report.reverted.push(original[i].name.clone());
            continue;
        }
        if swapped[i] {
            report.swapped.push(ObjectSwap {
                name: original[i].name.clone(),
                category: assets[i].category,
                from_variant: original[i].variant,
                to_variant: candidate.objects[i].variant,
                from_scale: original[i].scale,
                to_scale: candidate.objects[i].scale,
            });
        }
        if reseated[i] {
            report.reseated.push(original[i].name.clone());
        }
    }
    *scene = candidate;
    Ok(report)
}
