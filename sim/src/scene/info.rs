//! Summary of a scene: rooms, objects per room, categories, articulated objects.

use std::collections::BTreeMap;

use serde::Serialize;

use super::{SceneError, SceneFile};
use crate::assets::RoomType;

/// One room of a [`SceneInfo`].
///
/// ```
/// # use hearth_sim::scene::{GenerateOptions, SceneInfo, generate};
/// let info = SceneInfo::of(&generate(&GenerateOptions { seed: 0, rooms: 2, ..Default::default() }).unwrap());
/// assert!(info.rooms.iter().all(|r| r.area > 0.0));
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoomInfo {
    /// Name.
    pub name: String,
    /// Type.
    pub room_type: RoomType,
    /// Floor area, m².
    pub area: f64,
    /// Objects in the room.
    pub objects: usize,
}

/// What a scene holds (the JSON of `hearth scene info --json`).
///
/// ```
/// use hearth_sim::scene::{GenerateOptions, SceneInfo, generate};
/// let home = generate(&GenerateOptions { seed: 5, rooms: 3, ..Default::default() }).unwrap();
/// let info = SceneInfo::of(&home);
/// assert_eq!(info.objects, home.objects.len());
/// assert!(info.objects_per_room >= 40.0);
/// assert!(info.articulated.iter().any(|n| n.starts_with("door_")));
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneInfo {
    /// Scene name.
    pub name: String,
    /// Rooms with type, area and object count.
    pub rooms: Vec<RoomInfo>,
    /// Number of objects.
    pub objects: usize,
    /// Objects divided by rooms (0 without rooms).
    pub objects_per_room: f64,
    /// Objects not inside any room.
    pub unassigned: usize,
    /// Object count per category.
    pub categories: BTreeMap<String, usize>,
    /// Names of objects with moving joints.
    pub articulated: Vec<String>,
}

impl SceneInfo {
    /// Summarises a scene; an object belongs to the room it names, else to the room its
    /// position lies in. Objects of unknown categories count as not articulated.
    ///
    /// ```
    /// use hearth_sim::scene::{SceneFile, SceneInfo, SceneObject};
    /// let mut s = SceneFile::empty("one drawer unit");
    /// s.objects.push(SceneObject::new("n", "nightstand", 1, [0.0, 0.0, 0.0]));
    /// let info = SceneInfo::of(&s);
    /// assert_eq!(info.articulated, ["n"]);
    /// assert_eq!(info.unassigned, 1); // no rooms
    /// ```
    pub fn of(scene: &SceneFile) -> SceneInfo {
        let rooms = &scene.building.rooms;
        let mut per_room = vec![0usize; rooms.len()];
        let mut unassigned = 0;
        let mut categories = BTreeMap::new();
        let mut articulated = Vec::new();
        let mut joints_of: BTreeMap<(String, usize), bool> = BTreeMap::new();
        for o in &scene.objects {
            *categories.entry(o.category.clone()).or_insert(0) += 1;
            let by_name = o.room.as_ref().and_then(|n| rooms.iter().position(|r| &r.name == n));
            let xy = [o.position[0], o.position[1]];
            match by_name.or_else(|| rooms.iter().position(|r| r.contains(xy))) {
                Some(k) => per_room[k] += 1,
                None => unassigned += 1,
            }
            let moving = *joints_of.entry((o.category.clone(), o.variant)).or_insert_with(|| {
                crate::assets::Category::from_name(&o.category)
                    .and_then(|c| crate::assets::Asset::build(c, o.variant, 1.0).ok())
                    .is_some_and(|a| a.articulated)
            });
            if moving {
                articulated.push(o.name.clone());
            }
        }
        let room_infos: Vec<RoomInfo> = rooms
            .iter()
            .zip(per_room)
            .map(|(r, n)| RoomInfo {
                name: r.name.clone(),
                room_type: r.room_type,
                area: r.area(),
                objects: n,
            })
            .collect();
        SceneInfo {
            name: scene.name.clone(),
            objects_per_room: if rooms.is_empty() {
                0.0
            } else {
                scene.objects.len() as f64 / rooms.len() as f64
            },
            rooms: room_infos,
            objects: scene.objects.len(),
            unassigned,
            categories,
            articulated,
        }
    }

    /// The summary as pretty JSON.
    ///
    /// ```
    /// # use hearth_sim::scene::{SceneFile, SceneInfo};
    /// let j = SceneInfo::of(&SceneFile::empty("e")).to_json().unwrap();
    /// assert!(j.contains("\"objects_per_room\""));
    /// ```
    pub fn to_json(&self) -> Result<String, SceneError> {
        serde_json::to_string_pretty(self).map_err(|e| SceneError::invalid("scene info", e.to_string()))
    }
}
