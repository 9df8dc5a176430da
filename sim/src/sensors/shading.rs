//! Shading of the ray-cast camera: metallic-roughness materials under the scene's point and
//! directional lights (Lambert diffuse plus GGX specular), a constant sky/ground ambient term,
//! exposure, a Reinhard tone map and sRGB encoding.
//!
//! Light units: point lights in candela (irradiance = intensity / d²), directional lights in
//! lux; [`EXPOSURE`] scales irradiance into display range.

use parry3d::math::Vector;

use super::visuals::{PbrMaterial, SceneLight};

/// Scale from scene irradiance to display radiance.
pub const EXPOSURE: f32 = 0.12;
/// Ambient irradiance from the sky (above) and the ground (below), in scene units.
pub const AMBIENT_SKY: [f32; 3] = [1.6, 1.7, 1.9];
/// Ambient irradiance from below.
pub const AMBIENT_GROUND: [f32; 3] = [0.8, 0.75, 0.7];
/// Colour of pixels that see nothing (linear RGB, before tone mapping: a pale sky).
pub const BACKGROUND_SRGB: [u8; 3] = [178, 196, 214];

/// A light as seen from a surface point: unit direction towards the light and irradiance
/// (colour × intensity, before the cosine), and the distance to it (∞ for the sun).
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit vector from the point towards the light.
    pub to_light: Vector,
    /// Irradiance on a surface facing the light.
    pub irradiance: Vector,
    /// Distance to the light (f32::INFINITY for directional lights).
    pub distance: f32,
}

/// The lights as seen from `p`.
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
