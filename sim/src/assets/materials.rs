//! The material table: each visual material name maps to friction, restitution, density and a
//! base colour, so that physical properties follow from what an object is made of.
//!
//! Sources of the typical values:
//! - densities: The Engineering ToolBox, "Densities of Solids" and "Wood Species - Densities"
//!   (oak 600–900 kg/m³, steel 7850, marble 2560–2800, glass 2400–2800, porcelain 2300–2500,
//!   ABS plastic 1020–1080, natural rubber 920–1200); polyurethane foam 24–45 kg/m³ from the
//!   Polyurethane Foam Association's "Joint Industry Foam Standards"; upholstery, leather and
//!   foliage are effective bulk densities of the assembled part (cover, filling and air);
//! - friction: The Engineering ToolBox, "Friction and Friction Coefficients for Various Materials"
//!   (dry static coefficients against a like or common surface, rounded);
//! - restitution: typical drop-test coefficients of restitution (rubber ≈ 0.8, hard plastics
//!   ≈ 0.45, wood ≈ 0.4, ceramics and glass ≈ 0.3, soft goods ≈ 0.05), rounded.
//!
//! [`Material::ranges`] gives the span each property takes over the real materials a class
//! stands for, for domain randomisation: density spans are the sources' ranges above (oak,
//! carbon and stainless steels 7480–8050, marble, glass, porcelain, ABS, natural rubber, foam
//! grades; paper and board 700–1150 from the same density table); friction spans are the
//! sources' dry static ranges where the table gives one (wood on wood 0.25–0.5 widened to 0.6
//! for finished surfaces, steel on steel 0.5–0.8, rubber 0.8–1.16); the remaining spans
//! (soft goods, foliage, plaster, restitution of every class) are ±25–50 % around the typical
//! value, an assumption rather than a measurement. Every span contains the typical value.

use serde::{Deserialize, Serialize};

/// A material that parts of assets are made of.
///
/// ```
/// use hearth_sim::assets::Material;
/// let m: Material = "marble".parse().unwrap();
/// assert_eq!(m, Material::Marble);
/// assert!(m.props().density > 2000.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Material {
    /// Hardwood or veneered board.
    Wood,
    /// Steel (appliances, handles, frames).
    Metal,
    /// Polished marble (worktops).
    Marble,
    /// Upholstery fabric over foam (sofas, chairs, pillows).
    Fabric,
    /// Hard plastic (ABS).
    Plastic,
    /// Soda-lime glass.
    Glass,
    /// Porcelain and stoneware (dishes, toilets).
    Ceramic,
    /// Leather upholstery.
    Leather,
    /// Stone or ceramic tile (floors, bathtubs).
    Stone,
    /// Paper and board (books).
    Paper,
    /// Rubber (feet, mats).
    Rubber,
    /// Polyurethane foam (mattresses, cushions).
    Foam,
    /// Leaves and stems of plants.
    Foliage,
    /// Painted plaster on walls and ceilings.
    Plaster,
}

/// Physical and visual properties of a [`Material`].
///
/// ```
/// use hearth_sim::assets::Material;
/// let p = Material::Rubber.props();
/// assert!(p.friction > Material::Glass.props().friction);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialProps {
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Coefficient of restitution in [0, 1].
    pub restitution: f64,
    /// Density in kg/m³.
    pub density: f64,
    /// Base colour, RGBA in [0, 1].
    pub rgba: [f64; 4],
}

/// The span of each physical property over the real materials a [`Material`] class stands for
/// (see the module docs for sources): `[low, high]` pairs with `low ≤ typical ≤ high`.
///
/// ```
/// use hearth_sim::assets::Material;
/// let r = Material::Wood.ranges();
/// let p = Material::Wood.props();
/// assert!(r.density[0] <= p.density && p.density <= r.density[1]);
/// assert_eq!(Material::Metal.ranges().friction, [0.5, 0.8]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialRanges {
    /// Coulomb friction coefficient.
    pub friction: [f64; 2],
    /// Coefficient of restitution.
    pub restitution: [f64; 2],
    /// Density, kg/m³.
    pub density: [f64; 2],
}

const fn ranges(friction: [f64; 2], restitution: [f64; 2], density: [f64; 2]) -> MaterialRanges {
    MaterialRanges {
        friction,
        restitution,
        density,
    }
}

const fn props(friction: f64, restitution: f64, density: f64, rgba: [f64; 4]) -> MaterialProps {
    MaterialProps {
        friction,
        restitution,
        density,
        rgba,
    }
}

impl Material {
    /// Every material, in table order.
    ///
    /// ```
    /// assert!(hearth_sim::assets::Material::ALL.contains(&hearth_sim::assets::Material::Glass));
    /// ```
    pub const ALL: [Material; 14] = [
        Material::Wood,
        Material::Metal,
        Material::Marble,
        Material::Fabric,
        Material::Plastic,
        Material::Glass,
        Material::Ceramic,
        Material::Leather,
        Material::Stone,
        Material::Paper,
        Material::Rubber,
        Material::Foam,
        Material::Foliage,
        Material::Plaster,
    ];

    /// The name used in URDF `<material name=…>` and in scene files.
    ///
    /// ```
    /// assert_eq!(hearth_sim::assets::Material::Wood.name(), "wood");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Material::Wood => "wood",
            Material::Metal => "metal",
            Material::Marble => "marble",
            Material::Fabric => "fabric",
            Material::Plastic => "plastic",
            Material::Glass => "glass",
            Material::Ceramic => "ceramic",
            Material::Leather => "leather",
            Material::Stone => "stone",
            Material::Paper => "paper",
            Material::Rubber => "rubber",
            Material::Foam => "foam",
            Material::Foliage => "foliage",
            Material::Plaster => "plaster",
        }
    }

    /// Friction, restitution, density and colour (see the module docs for sources).
    ///
    /// ```
    /// assert_eq!(hearth_sim::assets::Material::Metal.props().density, 7850.0);
    /// ```
    pub fn props(self) -> MaterialProps {
        match self {
            Material::Wood => props(0.45, 0.4, 700.0, [0.55, 0.38, 0.22, 1.0]),
            Material::Metal => props(0.5, 0.3, 7850.0, [0.72, 0.73, 0.75, 1.0]),
            Material::Marble => props(0.4, 0.2, 2700.0, [0.92, 0.91, 0.88, 1.0]),
            Material::Fabric => props(0.7, 0.05, 80.0, [0.45, 0.5, 0.6, 1.0]),
            Material::Plastic => props(0.35, 0.45, 1050.0, [0.2, 0.2, 0.22, 1.0]),
            Material::Glass => props(0.4, 0.3, 2500.0, [0.75, 0.85, 0.9, 0.35]),
            Material::Ceramic => props(0.5, 0.3, 2400.0, [0.96, 0.96, 0.94, 1.0]),
            Material::Leather => props(0.6, 0.1, 860.0, [0.35, 0.2, 0.12, 1.0]),
            Material::Stone => props(0.6, 0.2, 2400.0, [0.6, 0.6, 0.58, 1.0]),
            Material::Paper => props(0.4, 0.1, 800.0, [0.85, 0.8, 0.7, 1.0]),
            Material::Rubber => props(1.0, 0.8, 1100.0, [0.1, 0.1, 0.1, 1.0]),
            Material::Foam => props(0.8, 0.05, 35.0, [0.95, 0.95, 0.92, 1.0]),
            Material::Foliage => props(0.6, 0.1, 100.0, [0.2, 0.55, 0.2, 1.0]),
            Material::Plaster => props(0.6, 0.2, 1200.0, [0.93, 0.92, 0.9, 1.0]),
        }
    }
}

impl Material {
    /// Spans of friction, restitution and density for randomisation (see
    /// [`MaterialRanges`]); each contains the typical value of [`Material::props`].
    ///
    /// ```
    /// use hearth_sim::assets::Material;
    /// for m in Material::ALL {
    ///     let (r, p) = (m.ranges(), m.props());
    ///     assert!(r.friction[0] <= p.friction && p.friction <= r.friction[1]);
    ///     assert!(r.restitution[0] <= p.restitution && p.restitution <= r.restitution[1]);
    /// }
    /// ```
    pub fn ranges(self) -> MaterialRanges {
        match self {
            Material::Wood => ranges([0.25, 0.6], [0.3, 0.5], [600.0, 900.0]),
            Material::Metal => ranges([0.5, 0.8], [0.2, 0.4], [7480.0, 8050.0]),
            Material::Marble => ranges([0.3, 0.5], [0.15, 0.3], [2560.0, 2800.0]),
            Material::Fabric => ranges([0.5, 0.9], [0.02, 0.1], [50.0, 120.0]),
            Material::Plastic => ranges([0.25, 0.5], [0.35, 0.55], [1020.0, 1080.0]),
            Material::Glass => ranges([0.3, 0.6], [0.2, 0.4], [2400.0, 2800.0]),
            Material::Ceramic => ranges([0.4, 0.65], [0.2, 0.4], [2300.0, 2500.0]),
            Material::Leather => ranges([0.45, 0.75], [0.05, 0.15], [700.0, 1000.0]),
            Material::Stone => ranges([0.45, 0.75], [0.1, 0.3], [2200.0, 2700.0]),
            Material::Paper => ranges([0.3, 0.5], [0.05, 0.15], [700.0, 1150.0]),
            Material::Rubber => ranges([0.8, 1.16], [0.6, 0.9], [920.0, 1200.0]),
            Material::Foam => ranges([0.6, 0.95], [0.02, 0.1], [24.0, 45.0]),
            Material::Foliage => ranges([0.4, 0.8], [0.05, 0.15], [60.0, 150.0]),
            Material::Plaster => ranges([0.45, 0.75], [0.1, 0.3], [1000.0, 1300.0]),
        }
    }
}

impl std::fmt::Display for Material {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The error of parsing an unknown material name.
///
/// ```
/// assert!("unobtainium".parse::<hearth_sim::assets::Material>().is_err());
/// ```
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown material `{0}` (known: wood, metal, marble, fabric, plastic, glass, ceramic, leather, stone, paper, rubber, foam, foliage, plaster)"
)]
/// ```
/// use hearth_sim::assets::{Material, UnknownMaterial};
/// let err = "jade".parse::<Material>().unwrap_err();
/// assert_eq!(err, UnknownMaterial("jade".into()));
/// assert!(err.to_string().contains("marble"));
/// ```
pub struct UnknownMaterial(pub String);

impl std::str::FromStr for Material {
    type Err = UnknownMaterial;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Material::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| UnknownMaterial(s.to_owned()))
    }
}
