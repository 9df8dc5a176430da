//! Visual material randomisation: every part of an object (its shapes sharing one material)
//! gets a new material of the same class (wood stays wood, metal stays metal), its base
//! colour, roughness and metalness drawn from ranges typical of the class ([`class_look`]).
//!
//! The draw for a part depends only on the seed, the instance name and the part's original
//! material, so every camera of a world (and a camera rebuilt later) shows the same look.
//! Geometry, semantic classes and instance ids are never touched; neither are the world's
//! body materials (the class stays what the scene says, so physics and the material table
//! agree).

use rand_pcg::Pcg64Mcg;

use super::config::VisualRandomizationConfig;
use super::error::RandomizeError;
use super::sampling::{Stream, stream, uniform};
use crate::assets::Material;
use crate::sensors::{Camera, PbrMaterial, SemanticClass, VisualScene};
use crate::world::World;

/// The ranges a material class's look is drawn from: base colour as hue (degrees),
/// saturation and value (HSV, linear), roughness and metalness.
///
/// ```
/// use hearth_sim::assets::Material;
/// use hearth_sim::randomize::class_look;
/// assert!(class_look(Material::Metal).metallic[0] > 0.8);
/// assert_eq!(class_look(Material::Wood).metallic, [0.0, 0.0]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClassLook {
    /// Hue range, degrees (may wrap past 360).
    pub hue: [f64; 2],
    /// Saturation range, `[0, 1]`.
    pub saturation: [f64; 2],
    /// Value (brightness) range, `[0, 1]`.
    pub value: [f64; 2],
    /// Perceptual roughness range.
    pub roughness: [f64; 2],
    /// Metalness range.
    pub metallic: [f64; 2],
}

const fn look(
    hue: [f64; 2],
    saturation: [f64; 2],
    value: [f64; 2],
    roughness: [f64; 2],
    metallic: [f64; 2],
) -> ClassLook {
    ClassLook {
        hue,
        saturation,
        value,
        roughness,
        metallic,
    }
}

/// The look ranges of a material class: woods from pale birch to dark walnut, steels and
/// aluminium (near-grey, metallic), white-to-grey marble, fabrics and plastics in any hue, and
/// so on. Every range contains the class's table colour, roughness and metalness.
///
/// ```
/// use hearth_sim::assets::Material;
/// let l = hearth_sim::randomize::class_look(Material::Foliage);
/// assert!(l.hue[0] >= 60.0 && l.hue[1] <= 160.0);
/// ```
pub fn class_look(m: Material) -> ClassLook {
    match m {
        Material::Wood => look([15.0, 45.0], [0.3, 0.75], [0.2, 0.8], [0.45, 0.8], [0.0, 0.0]),
        Material::Metal => look([0.0, 360.0], [0.0, 0.12], [0.45, 0.95], [0.15, 0.55], [0.85, 1.0]),
        Material::Marble => look([20.0, 60.0], [0.0, 0.1], [0.7, 0.97], [0.1, 0.35], [0.0, 0.0]),
        Material::Fabric => look([0.0, 360.0], [0.1, 0.6], [0.2, 0.85], [0.85, 1.0], [0.0, 0.0]),
        Material::Plastic => look([0.0, 360.0], [0.0, 0.8], [0.1, 0.9], [0.3, 0.6], [0.0, 0.0]),
        Material::Glass => look([170.0, 220.0], [0.0, 0.25], [0.7, 0.95], [0.02, 0.1], [0.0, 0.0]),
        Material::Ceramic => look([0.0, 360.0], [0.0, 0.3], [0.7, 0.98], [0.15, 0.35], [0.0, 0.0]),
        Material::Leather => look([10.0, 35.0], [0.3, 0.75], [0.1, 0.5], [0.45, 0.7], [0.0, 0.0]),
        Material::Stone => look([20.0, 60.0], [0.0, 0.2], [0.35, 0.75], [0.6, 0.85], [0.0, 0.0]),
        Material::Paper => look([0.0, 360.0], [0.05, 0.6], [0.3, 0.9], [0.75, 0.95], [0.0, 0.0]),
        Material::Rubber => look([0.0, 360.0], [0.0, 0.1], [0.03, 0.2], [0.8, 1.0], [0.0, 0.0]),
        Material::Foam => look([30.0, 60.0], [0.0, 0.15], [0.75, 0.98], [0.9, 1.0], [0.0, 0.0]),
        Material::Foliage => look([80.0, 140.0], [0.4, 0.8], [0.25, 0.6], [0.6, 0.85], [0.0, 0.0]),
        Material::Plaster => look([20.0, 60.0], [0.0, 0.15], [0.75, 0.97], [0.8, 0.95], [0.0, 0.0]),
    }
}

fn hsv_to_rgb(h: f64, s: f64, v: f64) -> [f64; 3] {
    let h = h.rem_euclid(360.0) / 60.0;
    let c = v * s;
    let x = c * (1.0 - (h % 2.0 - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m]
}

/// A material of class `m` drawn from its [`class_look`]; alpha is kept from `alpha`.
fn draw_class(m: Material, alpha: f32, rng: &mut Pcg64Mcg) -> PbrMaterial {
    let l = class_look(m);
    let rgb = hsv_to_rgb(uniform(rng, l.hue), uniform(rng, l.saturation), uniform(rng, l.value));
    PbrMaterial {
        base_color: [rgb[0] as f32, rgb[1] as f32, rgb[2] as f32, alpha],
        metallic: uniform(rng, l.metallic) as f32,
        roughness: uniform(rng, l.roughness).clamp(0.04, 1.0) as f32,
        class: Some(m),
    }
}

/// A material of no known class, jittered: brightness ×[0.75, 1.25], roughness ±0.15.
fn jitter(base: &PbrMaterial, rng: &mut Pcg64Mcg) -> PbrMaterial {
    let k = uniform(rng, [0.75, 1.25]) as f32;
    let mut m = *base;
    for c in &mut m.base_color[..3] {
        *c = (*c * k).clamp(0.0, 1.0);
    }
    m.roughness = (m.roughness + uniform(rng, [-0.15, 0.15]) as f32).clamp(0.04, 1.0);
    m
}

/// One draw of visual materials: a seed and which parts of the scene to change.
///
/// ```
/// use hearth_sim::randomize::{VisualRandomization, VisualRandomizationConfig};
/// use hearth_sim::sensors::VisualScene;
/// use hearth_sim::world::{World, WorldConfig};
/// use hearth_sim::scene::{SceneFile, SceneObject};
/// let mut scene = SceneFile::empty("one table");
/// scene.objects.push(SceneObject::new("table", "table", 0, [0.0, 0.0, 0.0]));
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.load_scene(&scene).unwrap();
/// let mut visuals = VisualScene::from_world(&world);
/// let before = visuals.items[visuals.items.len() - 1].material;
/// let config = VisualRandomizationConfig { enabled: true, ..Default::default() };
/// let changed = VisualRandomization::new(3, config).apply_to_scene(&mut visuals);
/// assert!(changed > 0);
/// let after = visuals.items[visuals.items.len() - 1].material;
/// assert_ne!(before.base_color, after.base_color);
/// assert_eq!(before.class, after.class);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct VisualRandomization {
    seed: u64,
    config: VisualRandomizationConfig,
}

impl VisualRandomization {
    /// A draw with its own seed.
    ///
    /// ```
    /// use hearth_sim::randomize::VisualRandomization;
    /// assert_ne!(VisualRandomization::new(1, Default::default()), VisualRandomization::new(2, Default::default()));
    /// ```
    pub fn new(seed: u64, config: VisualRandomizationConfig) -> Self {
        VisualRandomization { seed, config }
    }

    /// The new material of a part of `instance` (semantic class `semantic`) whose original
    /// material is `base`, or `None` when the configuration leaves it alone.
    ///
    /// ```
    /// use hearth_sim::assets::Material;
    /// use hearth_sim::randomize::{VisualRandomization, VisualRandomizationConfig};
    /// use hearth_sim::sensors::{PbrMaterial, SemanticClass};
    /// let v = VisualRandomization::new(1, VisualRandomizationConfig { enabled: true, ..Default::default() });
    /// let wood = PbrMaterial::of(Material::Wood);
    /// let a = v.material_for("table_0", SemanticClass::OBJECT, &wood).unwrap();
    /// assert_eq!(a, v.material_for("table_0", SemanticClass::OBJECT, &wood).unwrap());
    /// assert_eq!(a.class, Some(Material::Wood));
    /// assert!(v.material_for("building/wall/w", SemanticClass::WALL, &wood).is_none());
    /// ```
    pub fn material_for(&self, instance: &str, semantic: u32, base: &PbrMaterial) -> Option<PbrMaterial> {
        let c = &self.config;
        let wanted = match semantic {
            SemanticClass::FLOOR | SemanticClass::WALL | SemanticClass::CEILING => c.building,
            SemanticClass::ROBOT => c.robot,
            SemanticClass::BACKGROUND => false,
            _ => c.objects,
        };
        if !(c.enabled && wanted) {
            return None;
        }
        let [r, g, b, a] = base.base_color.map(f32::to_bits);
        let class = base.class.map_or("none", Material::name);
        let key = format!("{instance}|{class}|{r:08x}{g:08x}{b:08x}{a:08x}");
        let mut rng = stream(self.seed, 0, Stream::Visual, &key);
        Some(match base.class {
            Some(m) => draw_class(m, base.base_color[3], &mut rng),
            None => jitter(base, &mut rng),
        })
    }

    /// Replaces the materials of `scene`'s items in place; returns how many changed.
    ///
    /// ```
    /// use hearth_sim::randomize::VisualRandomization;
    /// let mut empty = hearth_sim::sensors::VisualScene::default();
    /// assert_eq!(VisualRandomization::new(1, Default::default()).apply_to_scene(&mut empty), 0);
    /// ```
    pub fn apply_to_scene(&self, scene: &mut VisualScene) -> usize {
        let mut changed = 0;
        for item in &mut scene.items {
            let name = scene
                .instances
                .get((item.instance as usize).wrapping_sub(1))
                .map_or("", |i| i.name.as_str());
            if let Some(m) = self.material_for(name, item.semantic, &item.material) {
                changed += usize::from(m != item.material);
                item.material = m;
            }
        }
        changed
    }

    /// Gives `camera` this draw's materials, computed from the world's own materials
    /// ([`VisualScene::from_world`]), so applying twice, or after another draw, gives the same
    /// result. Items the configuration leaves alone get their original material back. When
    /// the camera's items no longer match the world (models were spawned since it was built),
    /// the camera is rebuilt first ([`Camera::rebuild`]). Returns how many items differ from
    /// the world's materials.
    ///
    /// # Errors
    /// [`RandomizeError::Sensor`] when the camera refuses a material or cannot be rebuilt.
    ///
    /// ```
    /// use hearth_sim::randomize::{VisualRandomization, VisualRandomizationConfig};
    /// use hearth_sim::sensors::{Backend, Camera, CameraConfig, Mount, Preset};
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::{Isometry3, Point3};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.3; 3], &Isometry3::translation(2.0, 0.0, 0.3), true).unwrap();
    /// let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// config.backend = Backend::Raycast;
    /// config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(2.0, 0.0, 0.3)).unwrap());
    /// let mut camera = Camera::new(&world, None, config).unwrap();
    /// let v = VisualRandomization::new(1, VisualRandomizationConfig { enabled: true, building: true, ..Default::default() });
    /// assert!(v.apply_to_camera(&world, &mut camera).unwrap() > 0); // the crate and the ground
    /// ```
    pub fn apply_to_camera(&self, world: &World, camera: &mut Camera) -> Result<usize, RandomizeError> {
        let mut pristine = VisualScene::from_world(world);
        if pristine.items.len() != camera.scene().items.len() {
            camera.rebuild(world)?;
        }
        let changed = self.apply_to_scene(&mut pristine);
        for (i, item) in pristine.items.iter().enumerate() {
            if camera.scene().items[i].material != item.material {
                camera.set_material(i, item.material)?;
            }
        }
        Ok(changed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assets::Material;
    use rand::SeedableRng;

    #[test]
    fn table_looks_lie_in_their_class_ranges() {
        for m in Material::ALL {
            let l = class_look(m);
            let (metal, rough) = crate::sensors::metallic_roughness(m);
            assert!(l.metallic[0] <= metal as f64 && metal as f64 <= l.metallic[1], "{m}");
            assert!(
                l.roughness[0] <= rough as f64 + 1e-6 && rough as f64 <= l.roughness[1] + 1e-6,
                "{m}"
            );
            let mut rng = Pcg64Mcg::seed_from_u64(4);
            for _ in 0..50 {
                let d = draw_class(m, 1.0, &mut rng);
                assert!(d.base_color[..3].iter().all(|c| (0.0..=1.0).contains(c)), "{m}");
                assert!(d.roughness >= 0.04 && d.roughness <= 1.0);
                assert_eq!(d.class, Some(m));
            }
        }
    }

    #[test]
    fn hsv_primaries() {
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9);
        assert!(close(hsv_to_rgb(0.0, 1.0, 1.0), [1.0, 0.0, 0.0]));
        assert!(close(hsv_to_rgb(120.0, 1.0, 1.0), [0.0, 1.0, 0.0]));
        assert!(close(hsv_to_rgb(240.0, 1.0, 0.5), [0.0, 0.0, 0.5]));
        assert!(close(hsv_to_rgb(33.0, 0.0, 0.7), [0.7, 0.7, 0.7]));
    }
}
