//! The parametric asset library: household object categories, their shape variants and the
//! material table.
//!
//! Every asset is URDF text written in code from primitive parts (boxes, cylinders, spheres) and
//! parsed into a [`RobotModel`], so the simulator spawns objects exactly like robots and URDF
//! export needs nothing more. Moving parts are links with joints: drawers are prismatic, doors
//! and lids revolute, each with limits, damping and friction. Every link carries collision
//! shapes, visuals named by [`Material`], and an inertial whose mass is material density ×
//! part volume (× the solid fraction of hollow parts) with the matching inertia tensor.
//!
//! Asset frame: x out of the front, y to the left, z up; the origin is the centre of the
//! footprint at floor level (for windows, the centre of the sill).
//!
//! ```
//! use hearth_sim::assets::{Asset, Category};
//! let cabinet = Asset::build(Category::BottomCabinet, 1, 1.0).unwrap();
//! assert!(cabinet.articulated);
//! assert_eq!(cabinet.model.dof(), 3); // three drawers
//! assert!(cabinet.mass > 10.0);
//! ```

mod bath;
mod category;
mod furniture;
mod kitchen;
mod materials;
mod parts;
mod small;
mod structure;
pub(crate) mod writer;

use hearth_kinematics::{KinematicsError, Num, RobotModel};
use nalgebra::Vector3;

pub use category::{Category, Placement, RoomType};
pub use materials::{Material, MaterialProps, MaterialRanges, UnknownMaterial};
pub use writer::Surface;

/// Width of the wall opening a door variant fills, metres.
///
/// ```
/// assert_eq!(hearth_sim::assets::door_opening_width(1), 0.9);
/// ```
pub fn door_opening_width(variant: usize) -> f64 {
    structure::opening_width(true, variant)
}

/// Width of the wall opening a window variant fills, metres.
///
/// ```
/// assert_eq!(hearth_sim::assets::window_opening_width(0), 1.0);
/// ```
pub fn window_opening_width(variant: usize) -> f64 {
    structure::opening_width(false, variant)
}

/// Height of door openings and of window openings, metres.
///
/// ```
/// let (door, window) = hearth_sim::assets::opening_heights();
/// assert!(door > window);
/// ```
pub fn opening_heights() -> (f64, f64) {
    (structure::DOOR_HEIGHT, structure::WINDOW_HEIGHT)
}

/// Why an asset could not be built.
///
/// ```
/// use hearth_sim::assets::{Asset, AssetError, Category};
/// let err = Asset::build(Category::Sofa, 7, 1.0).unwrap_err();
/// assert!(matches!(err, AssetError::VariantOutOfRange { count: 3, .. }));
/// assert!(err.to_string().contains("sofa has 3 variants"));
/// ```
#[derive(Debug, thiserror::Error)]
pub enum AssetError {
    /// The variant index is not below the category's variant count.
    #[error("{category} has {count} variants; variant {variant} does not exist")]
    VariantOutOfRange {
        /// The category.
        category: Category,
        /// The variant asked for.
        variant: usize,
        /// How many variants the category has.
        count: usize,
    },
    /// The scale is not a finite number in (0.1, 10].
    #[error("scale {} of {category} is not a finite number in (0.1, 10]", Num(*scale))]
    BadScale {
        /// The category.
        category: Category,
        /// The scale asked for.
        scale: f64,
    },
    /// The written URDF did not load (a bug in the library; reported, never a panic).
    #[error("URDF of {category} variant {variant} does not load: {error}")]
    Urdf {
        /// The category.
        category: Category,
        /// The variant.
        variant: usize,
        /// The loader's error.
        error: Box<KinematicsError>,
    },
}

/// What to build: category, variant, uniform scale and optionally another main material.
///
/// ```
/// use hearth_sim::assets::{Asset, AssetSpec, Category, Material};
/// let spec = AssetSpec { material: Some(Material::Metal), ..AssetSpec::new(Category::Table, 3) };
/// let metal = Asset::build_spec(&spec).unwrap();
/// let wood = Asset::build(Category::Table, 3, 1.0).unwrap();
/// assert!(metal.mass > wood.mass);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AssetSpec {
    /// The category.
    pub category: Category,
    /// The shape variant, `0..category.variants()`.
    pub variant: usize,
    /// Uniform scale of every length (mass scales with its cube).
    pub scale: f64,
    /// Replaces the category's main material when set.
    pub material: Option<Material>,
}

impl AssetSpec {
    /// Variant `variant` of `category` at scale 1 in its own material.
    ///
    /// ```
    /// let s = hearth_sim::assets::AssetSpec::new(hearth_sim::assets::Category::Mug, 0);
    /// assert_eq!(s.scale, 1.0);
    /// ```
    pub fn new(category: Category, variant: usize) -> Self {
        AssetSpec {
            category,
            variant,
            scale: 1.0,
            material: None,
        }
    }
}

/// A built asset: its URDF text, the loaded model and derived figures.
///
/// ```
/// use hearth_sim::assets::{Asset, Category};
/// let fridge = Asset::build(Category::Fridge, 1, 1.0).unwrap();
/// assert!(fridge.urdf.contains("<joint name=\"door_0_hinge\" type=\"revolute\">"));
/// assert!(fridge.aabb_max[2] > 1.7);
/// ```
#[derive(Clone, Debug)]
pub struct Asset {
    /// The category.
    pub category: Category,
    /// The variant.
    pub variant: usize,
    /// The scale it was built at.
    pub scale: f64,
    /// The main material.
    pub material: Material,
    /// The URDF text (deterministic: same spec, same text).
    pub urdf: String,
    /// The URDF loaded.
    pub model: RobotModel,
    /// Lower corner of the bounding box of every collision shape, asset frame, joints at zero.
    pub aabb_min: Vector3<f64>,
    /// Upper corner of that bounding box.
    pub aabb_max: Vector3<f64>,
    /// Total mass, kg.
    pub mass: f64,
    /// Whether any joint moves.
    pub articulated: bool,
    /// Surfaces other objects can rest on, asset frame.
    pub surfaces: Vec<Surface>,
}

impl Asset {
    /// Builds variant `variant` of `category` at `scale` in its own material.
    ///
    /// ```
    /// use hearth_sim::assets::{Asset, Category};
    /// let a = Asset::build(Category::Laptop, 0, 1.0).unwrap();
    /// let b = Asset::build(Category::Laptop, 0, 1.0).unwrap();
    /// assert_eq!(a.urdf, b.urdf);
    /// assert!(Asset::build(Category::Laptop, 99, 1.0).is_err());
    /// ```
    pub fn build(category: Category, variant: usize, scale: f64) -> Result<Asset, AssetError> {
        Asset::build_spec(&AssetSpec {
            scale,
            ..AssetSpec::new(category, variant)
        })
    }

    /// Builds an asset from a full spec.
    ///
    /// ```
    /// use hearth_sim::assets::{Asset, AssetSpec, Category};
    /// let big = Asset::build_spec(&AssetSpec { scale: 2.0, ..AssetSpec::new(Category::Bowl, 0) }).unwrap();
    /// assert!(big.aabb_max[2] > 0.09);
    /// ```
    pub fn build_spec(spec: &AssetSpec) -> Result<Asset, AssetError> {
        let AssetSpec {
            category,
            variant,
            scale,
            material,
        } = *spec;
        if variant >= category.variants() {
            return Err(AssetError::VariantOutOfRange {
                category,
                variant,
                count: category.variants(),
            });
        }
        if !(scale.is_finite() && scale > 0.1 && scale <= 10.0) {
            return Err(AssetError::BadScale { category, scale });
        }
        let material = material.unwrap_or(category.material());
        let name = format!("{}_{variant}", category.name());
        let mut w = writer::UrdfWriter::new(&name, scale);
        write_parts(&mut w, category, variant, material);
        let written = w.finish();
        let model =
            RobotModel::from_urdf_str_with(&written.urdf, &name, None, &Default::default()).map_err(|error| {
                AssetError::Urdf {
                    category,
                    variant,
                    error: Box::new(error),
                }
            })?;
        Ok(Asset {
            category,
            variant,
            scale,
            material,
            urdf: written.urdf,
            model,
            aabb_min: written.aabb_min,
            aabb_max: written.aabb_max,
            mass: written.mass,
            articulated: written.moving_joints > 0,
            surfaces: written.surfaces,
        })
    }

    /// Half extents of the bounding box.
    ///
    /// ```
    /// let rug = hearth_sim::assets::Asset::build(hearth_sim::assets::Category::Rug, 0, 1.0).unwrap();
    /// assert!((rug.half_extents()[0] - 0.6).abs() < 1e-9);
    /// ```
    pub fn half_extents(&self) -> Vector3<f64> {
        (self.aabb_max - self.aabb_min) / 2.0
    }

    /// Names of the joints that move (drawer slides, door hinges, lids).
    ///
    /// ```
    /// let t = hearth_sim::assets::Asset::build(hearth_sim::assets::Category::Toilet, 0, 1.0).unwrap();
    /// assert_eq!(t.joint_names(), ["lid_hinge"]);
    /// ```
    pub fn joint_names(&self) -> &[String] {
        self.model.variable_names()
    }
}

fn write_parts(w: &mut writer::UrdfWriter, c: Category, v: usize, m: Material) {
    use Category as C;
    let f: fn(&mut writer::UrdfWriter, usize, Material) = match c {
        C::BottomCabinet => kitchen::bottom_cabinet,
        C::TopCabinet => kitchen::top_cabinet,
        C::Counter => kitchen::counter,
        C::Fridge => kitchen::fridge,
        C::Stove => kitchen::stove,
        C::Dishwasher => kitchen::dishwasher,
        C::Microwave => kitchen::microwave,
        C::Table => furniture::table,
        C::Chair => furniture::chair,
        C::Sofa => furniture::sofa,
        C::Bed => furniture::bed,
        C::Shelf => furniture::shelf,
        C::Bookcase => furniture::bookcase,
        C::Nightstand => furniture::nightstand,
        C::Dresser => furniture::dresser,
        C::Wardrobe => furniture::wardrobe,
        C::Desk => furniture::desk,
        C::TvStand => furniture::tv_stand,
        C::Tv => small::tv,
        C::Toilet => bath::toilet,
        C::Bathtub => bath::bathtub,
        C::Lamp => furniture::lamp,
        C::FloorLamp => furniture::floor_lamp,
        C::Plant => furniture::plant,
        C::Rug => furniture::rug,
        C::Door => structure::door,
        C::Window => structure::window,
        C::Bowl => small::bowl,
        C::Mug => small::mug,
        C::Plate => small::plate,
        C::Bottle => small::bottle,
        C::Book => small::book,
        C::Laptop => small::laptop,
        C::Vase => small::vase,
        C::Pot => small::pot,
    };
    f(w, v, m);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_variant_builds_with_positive_masses() {
        for &c in Category::ALL {
            for v in 0..c.variants() {
                let a = Asset::build(c, v, 1.0).unwrap_or_else(|e| panic!("{c} {v}: {e}"));
                for l in a.model.links() {
                    let i = l
                        .inertial
                        .as_ref()
                        .unwrap_or_else(|| panic!("{c} {v} link {} has no inertial", l.name));
                    assert!(i.mass > 0.0, "{c} {v} {}", l.name);
                    assert!(!l.collisions.is_empty(), "{c} {v} {}", l.name);
                }
            }
        }
    }
}
