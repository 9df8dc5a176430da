//! Shading of the ray-cast camera: metallic-roughness materials under the scene's point and
//! directional lights (Lambert diffuse plus GGX specular), a constant sky/ground ambient term,
//! exposure, a Reinhard tone map and sRGB encoding.
//!
//! Light units: point lights in candela (irradiance = intensity / d²), directional lights in
//! lux; [`EXPOSURE`] scales irradiance into display range.

use parry3d::math::Vector;

use super::visuals::{PbrMaterial, SceneLight};

/// Scale from scene irradiance to display radiance.
///
/// ```
/// use hearth_sim::sensors::shading::{EXPOSURE, to_srgb8};
/// use parry3d::math::Vector;
/// // A radiance that exposure scales to 1 tone-maps to ½, about 188 in sRGB.
/// let c = to_srgb8(Vector::splat(1.0 / (EXPOSURE * std::f32::consts::PI)));
/// assert!(c.iter().all(|v| (187..=189).contains(v)), "{c:?}");
/// ```
pub const EXPOSURE: f32 = 0.12;
/// Ambient irradiance from the sky, in scene units: what a surface facing straight up
/// receives (blended towards [`AMBIENT_GROUND`] as the normal turns down).
///
/// ```
/// # use hearth_sim::sensors::PbrMaterial;
/// let white = PbrMaterial { base_color: [1.0; 4], metallic: 0.0, roughness: 0.5, class: None };
/// use hearth_sim::sensors::shading::{AMBIENT_SKY, shade};
/// use parry3d::math::Vector;
/// let up = shade(&white, Vector::Z, Vector::Z, &[], false); // no lights: ambient only
/// assert!((up - Vector::from(AMBIENT_SKY) / std::f32::consts::PI).length() < 1e-6);
/// ```
pub const AMBIENT_SKY: [f32; 3] = [1.6, 1.7, 1.9];
/// Ambient irradiance from the ground: what a surface facing straight down receives.
///
/// ```
/// # use hearth_sim::sensors::PbrMaterial;
/// let white = PbrMaterial { base_color: [1.0; 4], metallic: 0.0, roughness: 0.5, class: None };
/// use hearth_sim::sensors::shading::{AMBIENT_GROUND, shade};
/// use parry3d::math::Vector;
/// let down = shade(&white, Vector::NEG_Z, Vector::NEG_Z, &[], false);
/// assert!((down - Vector::from(AMBIENT_GROUND) / std::f32::consts::PI).length() < 1e-6);
/// ```
pub const AMBIENT_GROUND: [f32; 3] = [0.8, 0.75, 0.7];
/// Colour of the pixels that see nothing, as sRGB bytes (a pale blue sky), the same for the
/// ray-cast camera and the wgpu camera ([`GpuCamera::SKY_RGB`](crate::sensors::GpuCamera::SKY_RGB)).
///
/// ```
/// use hearth_sim::sensors::shading::BACKGROUND_SRGB;
/// use hearth_sim::sensors::{CameraIntrinsics, Frame, Modality, ModalitySet, RaycastCamera, RenderOptions, VisualScene};
/// let k = CameraIntrinsics::new(8, 6, 60.0).unwrap();
/// let mut camera = RaycastCamera::new(&VisualScene::default(), k, RenderOptions::default()).unwrap();
/// let mut frame = Frame::default();
/// let rgb = ModalitySet::EMPTY.with(Modality::Rgb);
/// camera.render(&[], &nalgebra::Isometry3::identity(), rgb, &mut frame).unwrap(); // an empty scene
/// assert!(frame.rgb.chunks(3).all(|c| c == BACKGROUND_SRGB));
/// ```
pub const BACKGROUND_SRGB: [u8; 3] = [180, 200, 225];

/// A light as seen from a surface point: unit direction towards the light and irradiance
/// (colour × intensity, before the cosine), and the distance to it (∞ for the sun).
///
/// ```
/// use hearth_sim::sensors::SceneLight;
/// use hearth_sim::sensors::shading::light_at;
/// use parry3d::math::Vector;
/// let sun = SceneLight::Directional { direction: [0.0, 0.0, -1.0], color: [1.0; 3], intensity: 5.0 };
/// let s = light_at(&sun, Vector::ZERO);
/// assert_eq!((s.to_light, s.irradiance, s.distance), (Vector::Z, Vector::splat(5.0), f32::INFINITY));
/// ```
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit vector from the point towards the light.
    pub to_light: Vector,
    /// Irradiance on a surface facing the light.
    pub irradiance: Vector,
    /// Distance to the light (f32::INFINITY for directional lights).
    pub distance: f32,
}

/// A light as seen from the world point `p`.
///
/// ```
/// use hearth_sim::sensors::SceneLight;
/// use hearth_sim::sensors::shading::light_at;
/// use parry3d::math::Vector;
/// let lamp = SceneLight::Point { position: [0.0, 0.0, 2.0], color: [1.0; 3], intensity: 8.0 };
/// let s = light_at(&lamp, Vector::ZERO);
/// assert_eq!(s.to_light, Vector::Z);
/// assert_eq!(s.distance, 2.0);
/// assert_eq!(s.irradiance, Vector::splat(2.0)); // 8 cd at 2 m
/// ```
pub fn light_at(light: &SceneLight, p: Vector) -> LightSample {
    match *light {
        SceneLight::Point {
            position,
            color,
            intensity,
        } => {
            let d = Vector::from(position) - p;
            let dist2 = d.length_squared().max(1e-4);
            let dist = dist2.sqrt();
            LightSample {
                to_light: d / dist,
                irradiance: Vector::from(color) * (intensity / dist2),
                distance: dist,
            }
        }
        SceneLight::Directional {
            direction,
            color,
            intensity,
        } => LightSample {
            to_light: -Vector::from(direction).normalize_or_zero(),
            irradiance: Vector::from(color) * intensity,
            distance: f32::INFINITY,
        },
    }
}

/// GGX (Trowbridge-Reitz) normal distribution.
fn ggx(n_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = n_h * n_h * (a2 - 1.0) + 1.0;
    a2 / (std::f32::consts::PI * d * d).max(1e-7)
}

/// Smith-Schlick visibility term for GGX, already divided by 4 (n·l)(n·v).
fn visibility(n_l: f32, n_v: f32, alpha: f32) -> f32 {
    let k = alpha / 2.0;
    let gl = n_l / (n_l * (1.0 - k) + k);
    let gv = n_v / (n_v * (1.0 - k) + k);
    gl * gv / (4.0 * n_l * n_v).max(1e-5)
}

/// Linear radiance (before exposure) leaving a surface point towards the viewer.
///
/// `n` is the unit normal, `v` the unit vector towards the viewer, `lights` the light samples
/// that reach the point (shadowed ones left out), `pbr` switches GGX specular on.
///
/// ```
/// # use hearth_sim::sensors::PbrMaterial;
/// let white = PbrMaterial { base_color: [1.0; 4], metallic: 0.0, roughness: 0.5, class: None };
/// use hearth_sim::sensors::SceneLight;
/// use hearth_sim::sensors::shading::{light_at, shade};
/// use parry3d::math::Vector;
/// let sun = SceneLight::Directional { direction: [0.0, 0.0, -1.0], color: [1.0; 3], intensity: 5.0 };
/// let lights = [light_at(&sun, Vector::ZERO)];
/// let lit = shade(&white, Vector::Z, Vector::Z, &lights, true);
/// let unlit = shade(&white, Vector::Z, Vector::Z, &[], true);
/// assert!(lit.x > unlit.x);
/// let facing_away = shade(&white, Vector::NEG_Z, Vector::NEG_Z, &lights, true);
/// assert!(facing_away.x < unlit.x); // no sun, and ground ambient only
/// ```
pub fn shade(material: &PbrMaterial, n: Vector, v: Vector, lights: &[LightSample], pbr: bool) -> Vector {
    let base = Vector::new(material.base_color[0], material.base_color[1], material.base_color[2]);
    let metallic = material.metallic.clamp(0.0, 1.0);
    let alpha = material.roughness.clamp(0.04, 1.0).powi(2);
    let diffuse_albedo = if pbr { base * (1.0 - metallic) } else { base };
    let f0 = Vector::splat(0.04).lerp(base, metallic);
    let n_v = n.dot(v).max(1e-4);
    let mut out = Vector::ZERO;
    for l in lights {
        let n_l = n.dot(l.to_light);
        if n_l <= 0.0 {
            continue;
        }
        let mut brdf = diffuse_albedo / std::f32::consts::PI;
        if pbr {
            let h = (l.to_light + v).normalize_or_zero();
            let n_h = n.dot(h).max(0.0);
            let v_h = v.dot(h).max(0.0);
            let fresnel = f0 + (Vector::ONE - f0) * (1.0 - v_h).powi(5);
            brdf += fresnel * (ggx(n_h, alpha) * visibility(n_l, n_v, alpha));
        }
        out += brdf * l.irradiance * n_l;
    }
    // Hemisphere ambient: sky above, ground below, by the normal's z; metals reflect it.
    let t = 0.5 + 0.5 * n.z;
    let ambient = Vector::from(AMBIENT_GROUND).lerp(Vector::from(AMBIENT_SKY), t);
    let ambient_albedo = if pbr {
        diffuse_albedo + f0 * (1.0 - 0.5 * alpha)
    } else {
        base
    };
    out + ambient * ambient_albedo / std::f32::consts::PI
}

/// Entries of the sRGB encoding table.
const SRGB_LUT_SIZE: usize = 4096;

/// sRGB encoding of linear values in [0, 1], tabulated (12-bit input).
fn srgb_lut() -> &'static [u8; SRGB_LUT_SIZE] {
    static LUT: std::sync::OnceLock<[u8; SRGB_LUT_SIZE]> = std::sync::OnceLock::new();
    LUT.get_or_init(|| {
        let mut t = [0u8; SRGB_LUT_SIZE];
        for (i, out) in t.iter_mut().enumerate() {
            let x = i as f32 / (SRGB_LUT_SIZE - 1) as f32;
            let s = if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            };
            *out = (s * 255.0 + 0.5) as u8;
        }
        t
    })
}

/// Exposure, Reinhard tone map and sRGB encoding of a linear radiance.
///
/// ```
/// use hearth_sim::sensors::shading::to_srgb8;
/// use parry3d::math::Vector;
/// assert_eq!(to_srgb8(Vector::ZERO), [0, 0, 0]);
/// let c = to_srgb8(Vector::new(1e6, 1.0, -1.0)); // tone-mapped, clamped below at 0
/// assert!(c[0] >= 254 && c[1] > 0 && c[2] == 0);
/// ```
pub fn to_srgb8(radiance: Vector) -> [u8; 3] {
    let c = radiance * EXPOSURE * std::f32::consts::PI;
    let lut = srgb_lut();
    let m = |x: f32| {
        let x = (x.max(0.0) / (1.0 + x.max(0.0))).min(1.0);
        lut[(x * (SRGB_LUT_SIZE - 1) as f32 + 0.5) as usize]
    };
    [m(c.x), m(c.y), m(c.z)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assets::Material;

    #[test]
    fn lit_side_is_brighter_and_colour_follows_the_material() {
        let sun = SceneLight::Directional {
            direction: [0.0, 0.0, -1.0],
            color: [1.0; 3],
            intensity: 5.0,
        };
        let up = Vector::Z;
        let lights = [light_at(&sun, Vector::ZERO)];
        let red = PbrMaterial {
            base_color: [0.8, 0.05, 0.05, 1.0],
            ..PbrMaterial::of(Material::Plastic)
        };
        let lit = to_srgb8(shade(&red, up, up, &lights, true));
        let unlit = to_srgb8(shade(&red, up, up, &[], true));
        assert!(lit[0] > unlit[0], "{lit:?} vs {unlit:?}");
        assert!(lit[0] > lit[1] + 50 && lit[0] > lit[2] + 50, "{lit:?}");
        assert!(lit[0] < 255, "not blown out: {lit:?}");
    }
}
