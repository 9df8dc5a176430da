//! Object categories: names, variant counts, the rooms they belong in and how they are placed.

use serde::{Deserialize, Serialize};

use super::Material;

/// The type of a room, as scene files and the home generator use it.
///
/// ```
/// use hearth_sim::assets::RoomType;
/// assert_eq!(RoomType::LivingRoom.name(), "living_room");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RoomType {
    /// Kitchen.
    Kitchen,
    /// Living room.
    LivingRoom,
    /// Bedroom.
    Bedroom,
    /// Bathroom.
    Bathroom,
    /// Corridor or hall.
    Corridor,
    /// Dining room.
    DiningRoom,
    /// Study or home office.
    Office,
}

impl RoomType {
    /// The snake-case name used in scene files.
    ///
    /// ```
    /// assert_eq!(hearth_sim::assets::RoomType::Kitchen.name(), "kitchen");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            RoomType::Kitchen => "kitchen",
            RoomType::LivingRoom => "living_room",
            RoomType::Bedroom => "bedroom",
            RoomType::Bathroom => "bathroom",
            RoomType::Corridor => "corridor",
            RoomType::DiningRoom => "dining_room",
            RoomType::Office => "office",
        }
    }
}

/// How an object of a category is placed in a room.
///
/// ```
/// use hearth_sim::assets::{Category, Placement};
/// assert_eq!(Category::Mug.placement(), Placement::OnSurface);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// On the floor with its back (−x side) against a wall.
    AgainstWall,
    /// On the floor, free standing (clusters, room interior).
    Free,
    /// Resting on a support surface of another object.
    OnSurface,
    /// Flat on the floor; furniture may stand on it.
    FloorCovering,
    /// Mounted on a wall at this height of its bottom above the floor.
    WallMounted {
        /// Height of the object's bottom above the floor, metres.
        z: f64,
    },
    /// Filling an opening of a wall (doors, windows).
    InWall,
}

macro_rules! categories {
    ($($variant:ident => $name:literal, $count:literal, $mat:ident, $place:expr, [$($room:ident),*];)*) => {
        /// An object category of the asset library.
        ///
        /// ```
        /// use hearth_sim::assets::Category;
        /// assert!(Category::ALL.len() >= 30);
        /// assert_eq!(Category::from_name("fridge"), Some(Category::Fridge));
        /// ```
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
        #[serde(rename_all = "snake_case")]
        pub enum Category {
            $(
                #[doc = concat!("A ", $name, ".")]
                $variant,
            )*
        }

        impl Category {
            /// Every category.
            ///
            /// ```
            /// assert!(hearth_sim::assets::Category::ALL.contains(&hearth_sim::assets::Category::Door));
            /// ```
            pub const ALL: &'static [Category] = &[$(Category::$variant),*];

            /// The snake-case name used in scene files.
            ///
            /// ```
            /// assert_eq!(hearth_sim::assets::Category::BottomCabinet.name(), "bottom_cabinet");
            /// ```
            pub fn name(self) -> &'static str {
                match self {
                    $(Category::$variant => $name,)*
                }
            }

            /// How many shape variants the category has (variant indices are `0..variants()`).
            ///
            /// ```
            /// use hearth_sim::assets::Category;
            /// assert!(Category::ALL.iter().all(|c| c.variants() >= 3));
            /// ```
            pub fn variants(self) -> usize {
                match self {
                    $(Category::$variant => $count,)*
                }
            }

            /// The main material of the category (its body; handles, glass and so on differ).
            ///
            /// ```
            /// use hearth_sim::assets::{Category, Material};
            /// assert_eq!(Category::Book.material(), Material::Paper);
            /// ```
            pub fn material(self) -> Material {
                match self {
                    $(Category::$variant => Material::$mat,)*
                }
            }

            /// How objects of this category are placed.
            ///
            /// ```
            /// use hearth_sim::assets::{Category, Placement};
            /// assert_eq!(Category::Door.placement(), Placement::InWall);
            /// ```
            pub fn placement(self) -> Placement {
                match self {
                    $(Category::$variant => $place,)*
                }
            }

            /// The room types the category belongs in (empty: anywhere).
            ///
            /// ```
            /// use hearth_sim::assets::{Category, RoomType};
            /// assert!(Category::Fridge.room_types().contains(&RoomType::Kitchen));
            /// ```
            pub fn room_types(self) -> &'static [RoomType] {
                match self {
                    $(Category::$variant => &[$(RoomType::$room),*],)*
                }
            }
        }
    };
}

use Placement::{AgainstWall, FloorCovering, Free, InWall, OnSurface};

categories! {
    BottomCabinet => "bottom_cabinet", 4, Wood, AgainstWall, [Kitchen, DiningRoom, Bathroom];
    TopCabinet => "top_cabinet", 3, Wood, Placement::WallMounted { z: 1.45 }, [Kitchen, Bathroom];
    Counter => "counter", 3, Wood, AgainstWall, [Kitchen, Bathroom];
    Fridge => "fridge", 3, Metal, AgainstWall, [Kitchen];
    Stove => "stove", 3, Metal, AgainstWall, [Kitchen];
    Dishwasher => "dishwasher", 3, Metal, AgainstWall, [Kitchen];
    Microwave => "microwave", 3, Metal, OnSurface, [Kitchen];
    Table => "table", 4, Wood, Free, [Kitchen, DiningRoom, LivingRoom];
    Chair => "chair", 3, Wood, Free, [Kitchen, DiningRoom, LivingRoom, Office, Bedroom];
    Sofa => "sofa", 3, Fabric, AgainstWall, [LivingRoom];
    Bed => "bed", 3, Wood, AgainstWall, [Bedroom];
    Shelf => "shelf", 3, Wood, AgainstWall, [LivingRoom, Kitchen, Office, Bathroom, Bedroom];
    Bookcase => "bookcase", 3, Wood, AgainstWall, [LivingRoom, Office, Bedroom];
    Nightstand => "nightstand", 3, Wood, AgainstWall, [Bedroom];
    Dresser => "dresser", 3, Wood, AgainstWall, [Bedroom];
    Wardrobe => "wardrobe", 3, Wood, AgainstWall, [Bedroom];
    Desk => "desk", 3, Wood, AgainstWall, [Office, Bedroom];
    TvStand => "tv_stand", 3, Wood, AgainstWall, [LivingRoom];
    Tv => "tv", 3, Plastic, OnSurface, [LivingRoom];
    Toilet => "toilet", 3, Ceramic, AgainstWall, [Bathroom];
    Bathtub => "bathtub", 3, Ceramic, AgainstWall, [Bathroom];
    Lamp => "lamp", 3, Metal, OnSurface, [LivingRoom, Bedroom, Office];
    FloorLamp => "floor_lamp", 3, Metal, Free, [LivingRoom, Bedroom, Office];
    Plant => "plant", 3, Ceramic, Free, [LivingRoom, Office, Corridor, DiningRoom];
    Rug => "rug", 3, Fabric, FloorCovering, [LivingRoom, Bedroom, Corridor, Bathroom];
    Door => "door", 3, Wood, InWall, [];
    Window => "window", 3, Wood, InWall, [];
    Bowl => "bowl", 3, Ceramic, OnSurface, [Kitchen, DiningRoom];
    Mug => "mug", 3, Ceramic, OnSurface, [Kitchen, DiningRoom, Office];
    Plate => "plate", 3, Ceramic, OnSurface, [Kitchen, DiningRoom];
    Bottle => "bottle", 3, Glass, OnSurface, [Kitchen, DiningRoom, Bathroom];
    Book => "book", 4, Paper, OnSurface, [LivingRoom, Office, Bedroom];
    Laptop => "laptop", 3, Plastic, OnSurface, [Office, Bedroom, LivingRoom];
    Vase => "vase", 3, Ceramic, OnSurface, [LivingRoom, DiningRoom, Bedroom];
    Pot => "pot", 3, Metal, OnSurface, [Kitchen];
}

impl Category {
    /// Looks a category up by its scene-file name.
    ///
    /// ```
    /// use hearth_sim::assets::Category;
    /// assert_eq!(Category::from_name("tv_stand"), Some(Category::TvStand));
    /// assert_eq!(Category::from_name("spaceship"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Category> {
        Category::ALL.iter().copied().find(|c| c.name() == name)
    }
}

impl std::fmt::Display for Category {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
