//! [`VisualScene`]: every visual shape of the world (building, objects, robots) with its
//! material, semantic class and instance id, and where it is now.
//!
//! Both camera backends draw from it: the wgpu renderer tessellates the shapes once and moves
//! them each frame; the ray caster puts them in a BVH. Shapes are attached to rapier bodies
//! (model links, building pieces, boxes), so they follow physics; static visuals
//! ([`World::static_visuals`]) stay put.

use std::sync::Arc;

use hearth_kinematics::{Geometry, TriangleMesh, from_pose};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rapier3d::prelude::RigidBodyHandle;

use crate::assets::{Category, Material};
use crate::scene::{Light, LightKind};
use crate::world::World;

/// A visual shape in its own frame.
///
/// ```
/// use hearth_sim::sensors::VisualShape;
/// let s = VisualShape::Cylinder { radius: 0.1, half_length: 0.2 };
/// assert!(matches!(s, VisualShape::Cylinder { .. }));
/// ```
#[derive(Clone, Debug)]
pub enum VisualShape {
    /// Box with these half extents.
    Box {
        /// Half extents along x, y, z.
        half: [f32; 3],
    },
    /// Cylinder along the local z axis.
    Cylinder {
        /// Radius.
        radius: f32,
        /// Half of the length.
        half_length: f32,
    },
    /// Sphere.
    Sphere {
        /// Radius.
        radius: f32,
    },
    /// Capsule along the local z axis.
    Capsule {
        /// Radius.
        radius: f32,
        /// Half of the cylindrical part's length.
        half_length: f32,
    },
    /// Triangle mesh (already scaled).
    Mesh(Arc<TriangleMesh>),
}

/// A metallic-roughness material.
///
/// ```
/// use hearth_sim::assets::Material;
/// use hearth_sim::sensors::PbrMaterial;
/// let m = PbrMaterial::of(Material::Metal);
/// assert_eq!(m.metallic, 1.0);
/// assert!(PbrMaterial::of(Material::Fabric).roughness > 0.8);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PbrMaterial {
    /// Linear base colour, RGBA in [0, 1].
    pub base_color: [f32; 4],
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// Perceptual roughness in [0.04, 1].
    pub roughness: f32,
    /// The material class, when the visual names one of the table's materials.
    pub class: Option<Material>,
}

/// Metalness and roughness of each material class (typical values of metallic-roughness
/// material libraries, rounded).
///
/// ```
/// use hearth_sim::{assets::Material, sensors::metallic_roughness};
/// assert_eq!(metallic_roughness(Material::Metal).0, 1.0);
/// let (metallic, roughness) = metallic_roughness(Material::Rubber);
/// assert!(metallic == 0.0 && roughness > metallic_roughness(Material::Glass).1);
/// ```
pub fn metallic_roughness(m: Material) -> (f32, f32) {
    match m {
        Material::Metal => (1.0, 0.35),
        Material::Marble => (0.0, 0.2),
        Material::Glass => (0.0, 0.05),
        Material::Ceramic => (0.0, 0.25),
        Material::Plastic => (0.0, 0.45),
        Material::Wood => (0.0, 0.6),
        Material::Leather => (0.0, 0.55),
        Material::Stone => (0.0, 0.7),
        Material::Rubber => (0.0, 0.9),
        Material::Paper | Material::Plaster => (0.0, 0.85),
        Material::Fabric | Material::Foam => (0.0, 0.95),
        Material::Foliage => (0.0, 0.75),
    }
}

impl PbrMaterial {
    /// The table material with its base colour.
    ///
    /// ```
    /// use hearth_sim::{assets::Material, sensors::PbrMaterial};
    /// let m = PbrMaterial::of(Material::Wood);
    /// assert_eq!(m.class, Some(Material::Wood));
    /// assert_eq!((m.metallic, m.roughness), hearth_sim::sensors::metallic_roughness(Material::Wood));
    /// ```
    pub fn of(m: Material) -> Self {
        let (metallic, roughness) = metallic_roughness(m);
        let c = m.props().rgba;
        Self {
            base_color: c.map(|x| x as f32),
            metallic,
            roughness,
            class: Some(m),
        }
    }

    /// A URDF visual's material: its class when the name is a table material (`wood`), its
    /// colour when given, otherwise a grey; names containing `metal` are metallic.
    ///
    /// ```
    /// use hearth_sim::{assets::Material, sensors::PbrMaterial};
    /// assert_eq!(PbrMaterial::from_urdf(Some("wood"), None), PbrMaterial::of(Material::Wood));
    /// let steel = PbrMaterial::from_urdf(Some("brushed_steel"), Some([0.2, 0.3, 0.4, 1.0]));
    /// assert_eq!((steel.metallic, steel.class), (1.0, None));
    /// assert_eq!(steel.base_color, [0.2, 0.3, 0.4, 1.0]);
    /// assert_eq!(PbrMaterial::from_urdf(None, None).base_color, [0.6, 0.6, 0.6, 1.0]);
    /// ```
    pub fn from_urdf(name: Option<&str>, rgba: Option<[f64; 4]>) -> Self {
        let class = name.and_then(|n| n.parse::<Material>().ok());
        let mut m = match class {
            Some(c) => Self::of(c),
            None => {
                let metal = name.is_some_and(|n| n.contains("metal") || n.contains("steel"));
                Self {
                    base_color: [0.6, 0.6, 0.6, 1.0],
                    metallic: if metal { 1.0 } else { 0.0 },
                    roughness: if metal { 0.35 } else { 0.5 },
                    class: None,
                }
            }
        };
        if let Some(c) = rgba {
            m.base_color = c.map(|x| x.clamp(0.0, 1.0) as f32);
        }
        m
    }
}

/// Semantic classes: 0 background, building parts, robots, then one class per asset
/// [`Category`] (id = [`SemanticClass::FIRST_CATEGORY`] + its index in [`Category::ALL`]).
///
/// ```
/// use hearth_sim::assets::Category;
/// use hearth_sim::sensors::SemanticClass;
/// let id = SemanticClass::of_category(Category::Fridge);
/// assert_eq!(SemanticClass::name(id), Some("fridge"));
/// assert_eq!(SemanticClass::id("wall"), Some(SemanticClass::WALL));
/// assert_eq!(SemanticClass::name(0), Some("background"));
/// ```
#[derive(Clone, Copy, Debug)]
pub struct SemanticClass;

impl SemanticClass {
    /// Nothing hit.
    ///
    /// ```
    /// use hearth_sim::sensors::SemanticClass;
    /// assert_eq!(SemanticClass::name(SemanticClass::BACKGROUND), Some("background"));
    /// ```
    pub const BACKGROUND: u32 = 0;
    /// Floors and the ground.
    ///
    /// ```
    /// # use hearth_sim::sensors::VisualScene;
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
    /// let scene = VisualScene::from_world(&world);
    /// use hearth_sim::sensors::SemanticClass;
    /// assert_eq!(scene.items[0].semantic, SemanticClass::FLOOR); // the ground
    /// ```
    pub const FLOOR: u32 = 1;
    /// Walls.
    ///
    /// ```
    /// use hearth_sim::sensors::SemanticClass;
    /// assert_eq!(SemanticClass::id("wall"), Some(SemanticClass::WALL));
    /// ```
    pub const WALL: u32 = 2;
    /// Ceilings.
    ///
    /// ```
    /// use hearth_sim::sensors::SemanticClass;
    /// assert_eq!(SemanticClass::name(SemanticClass::CEILING), Some("ceiling"));
    /// ```
    pub const CEILING: u32 = 3;
    /// Robots.
    ///
    /// ```
    /// use hearth_sim::sensors::SemanticClass;
    /// assert_eq!(SemanticClass::of_model("fetch"), SemanticClass::ROBOT);
    /// ```
    pub const ROBOT: u32 = 4;
    /// Objects of no known category.
    ///
    /// ```
    /// # use hearth_sim::sensors::VisualScene;
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
    /// let scene = VisualScene::from_world(&world);
    /// use hearth_sim::sensors::SemanticClass;
    /// assert_eq!(scene.items[1].semantic, SemanticClass::OBJECT); // a plain box
    /// ```
    pub const OBJECT: u32 = 5;
    /// Id of the first asset category.
    ///
    /// ```
    /// use hearth_sim::{assets::Category, sensors::SemanticClass};
    /// assert_eq!(SemanticClass::of_category(Category::ALL[0]), SemanticClass::FIRST_CATEGORY);
    /// ```
    pub const FIRST_CATEGORY: u32 = 10;

    /// The class id of an asset category.
    ///
    /// ```
    /// use hearth_sim::{assets::Category, sensors::SemanticClass};
    /// let id = SemanticClass::of_category(Category::ALL[2]);
    /// assert_eq!(id, SemanticClass::FIRST_CATEGORY + 2);
    /// assert_eq!(SemanticClass::name(id), Some(Category::ALL[2].name()));
    /// ```
    pub fn of_category(c: Category) -> u32 {
        let i = Category::ALL.iter().position(|&x| x == c).unwrap_or(0);
        Self::FIRST_CATEGORY + i as u32
    }

    /// The name of a class id.
    ///
    /// ```
    /// use hearth_sim::sensors::SemanticClass;
    /// assert_eq!(SemanticClass::name(SemanticClass::ROBOT), Some("robot"));
    /// assert_eq!(SemanticClass::name(7), None); // between the building classes and the categories
    /// assert_eq!(SemanticClass::name(u32::MAX), None);
    /// ```
    pub fn name(id: u32) -> Option<&'static str> {
        match id {
            Self::BACKGROUND => Some("background"),
            Self::FLOOR => Some("floor"),
            Self::WALL => Some("wall"),
            Self::CEILING => Some("ceiling"),
            Self::ROBOT => Some("robot"),
            Self::OBJECT => Some("object"),
            _ => id
                .checked_sub(Self::FIRST_CATEGORY)
                .and_then(|i| Category::ALL.get(i as usize))
                .map(|c| c.name()),
        }
    }

    /// The id of a class name.
    ///
    /// ```
    /// use hearth_sim::sensors::SemanticClass;
    /// assert_eq!(SemanticClass::id("floor"), Some(SemanticClass::FLOOR));
    /// assert_eq!(SemanticClass::id("spaceship"), None);
    /// ```
    pub fn id(name: &str) -> Option<u32> {
        (0..Self::FIRST_CATEGORY + Category::ALL.len() as u32).find(|&i| Self::name(i) == Some(name))
    }

    /// Every class as (id, name).
    ///
    /// ```
    /// use hearth_sim::{assets::Category, sensors::SemanticClass};
    /// let all = SemanticClass::all();
    /// assert_eq!(all[0], (0, "background"));
    /// assert_eq!(all.len(), 6 + Category::ALL.len());
    /// ```
    pub fn all() -> Vec<(u32, &'static str)> {
        (0..Self::FIRST_CATEGORY + Category::ALL.len() as u32)
            .filter_map(|i| Self::name(i).map(|n| (i, n)))
            .collect()
    }

    /// The class of a model by its model name (`fridge_2` → fridge, built-in robots → robot).
    ///
    /// ```
    /// use hearth_sim::{assets::Category, sensors::SemanticClass};
    /// assert_eq!(SemanticClass::of_model("fridge_2"), SemanticClass::of_category(Category::Fridge));
    /// assert_eq!(SemanticClass::of_model("turtlebot"), SemanticClass::ROBOT);
    /// assert_eq!(SemanticClass::of_model("crate"), SemanticClass::OBJECT);
    /// ```
    pub fn of_model(model_name: &str) -> u32 {
        if hearth_kinematics::builtin_names().contains(&model_name) {
            return Self::ROBOT;
        }
        let base = model_name
            .rsplit_once('_')
            .filter(|(_, n)| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
            .map_or(model_name, |(b, _)| b);
        Category::from_name(base).map_or(Self::OBJECT, Self::of_category)
    }

    fn of_body_name(name: &str) -> u32 {
        let rest = name.strip_prefix(crate::world::BUILDING_PREFIX).unwrap_or(name);
        if name == "ground" || rest.starts_with("floor/") {
            Self::FLOOR
        } else if rest.starts_with("wall/") {
            Self::WALL
        } else if rest.starts_with("ceiling/") {
            Self::CEILING
        } else {
            Self::OBJECT
        }
    }
}

/// One visual shape and what it is.
///
/// ```
/// # use hearth_sim::sensors::VisualScene;
/// # use hearth_sim::world::{World, WorldConfig};
/// # use nalgebra::Isometry3;
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
/// let scene = VisualScene::from_world(&world);
/// use hearth_sim::sensors::VisualShape;
/// let item = &scene.items[1]; // the crate
/// assert!(item.body.is_some()); // moves with its body
/// assert!(matches!(item.shape, VisualShape::Box { half } if half == [0.1; 3]));
/// assert_eq!(scene.instances[item.instance as usize - 1].name, "crate");
/// ```
#[derive(Clone, Debug)]
pub struct VisualItem {
    /// The body it is attached to (`None`: a static visual, `local` is its world pose).
    pub body: Option<RigidBodyHandle>,
    /// Pose of the shape in the body frame (or the world, for static visuals).
    pub local: Isometry3<f64>,
    /// The shape.
    pub shape: VisualShape,
    /// Its material.
    pub material: PbrMaterial,
    /// Semantic class id ([`SemanticClass`]).
    pub semantic: u32,
    /// Instance id (1-based index into [`VisualScene::instances`]).
    pub instance: u32,
}

/// A thing with an instance id: a model (robot or object), a building piece, a box.
///
/// ```
/// # use hearth_sim::sensors::VisualScene;
/// # use hearth_sim::world::{World, WorldConfig};
/// # use nalgebra::Isometry3;
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
/// let scene = VisualScene::from_world(&world);
/// use hearth_sim::sensors::Instance;
/// let crate_ = Instance { name: "crate".into(), semantic: scene.items[1].semantic };
/// assert_eq!(scene.instances[1], crate_);
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Instance {
    /// Model instance name or body name.
    pub name: String,
    /// Its semantic class id.
    pub semantic: u32,
}

/// A light in the form renderers use.
///
/// ```
/// # use hearth_sim::sensors::VisualScene;
/// # use hearth_sim::world::{World, WorldConfig};
/// # use nalgebra::Isometry3;
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
/// let scene = VisualScene::from_world(&world);
/// use hearth_sim::sensors::SceneLight;
/// // A world without lights gets the default sun.
/// assert!(matches!(scene.lights[..], [SceneLight::Directional { .. }]));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SceneLight {
    /// Point light at `position` with `intensity` (candela).
    Point {
        /// World position.
        position: [f32; 3],
        /// Linear RGB colour.
        color: [f32; 3],
        /// Candela.
        intensity: f32,
    },
    /// Directional light travelling along `direction`.
    Directional {
        /// Unit direction the light travels.
        direction: [f32; 3],
        /// Linear RGB colour.
        color: [f32; 3],
        /// Illuminance (lux).
        intensity: f32,
    },
}

/// The lights used when a world has none: a sun from above and the side.
///
/// ```
/// use hearth_sim::sensors::{SceneLight, default_lights};
/// let [SceneLight::Directional { direction, .. }] = default_lights()[..] else { unreachable!() };
/// assert!(direction[2] < 0.0); // shining downwards
/// assert!((direction.iter().map(|d| d * d).sum::<f32>() - 1.0).abs() < 1e-6);
/// ```
pub fn default_lights() -> Vec<SceneLight> {
    let d = Vector3::new(0.3f32, 0.4, -1.0).normalize();
    vec![SceneLight::Directional {
        direction: [d.x, d.y, d.z],
        color: [1.0, 1.0, 0.97],
        intensity: 6.0,
    }]
}

/// Converts scene lights (spot lights become point lights at their position).
///
/// ```
/// use hearth_sim::scene::{Light, LightKind};
/// use hearth_sim::sensors::{SceneLight, scene_lights};
/// let spot = Light {
///     name: "lamp".into(),
///     kind: LightKind::Spot,
///     position: [1.0, 2.0, 2.5],
///     direction: Some([0.0, 0.0, -1.0]),
///     color: [1.0; 3],
///     intensity: 50.0,
/// };
/// let lights = scene_lights(&[spot]);
/// assert_eq!(lights, vec![SceneLight::Point { position: [1.0, 2.0, 2.5], color: [1.0; 3], intensity: 50.0 }]);
/// ```
pub fn scene_lights(lights: &[Light]) -> Vec<SceneLight> {
    lights
        .iter()
        .map(|l| {
            let color = l.color.map(|c| c as f32);
            match (l.kind, l.direction) {
                (LightKind::Directional, Some(d)) => {
                    let v = Vector3::from(d).cast::<f32>();
                    let v = v.try_normalize(1e-9).unwrap_or(-Vector3::z());
                    SceneLight::Directional {
                        direction: [v.x, v.y, v.z],
                        color,
                        intensity: l.intensity as f32,
                    }
                }
                _ => SceneLight::Point {
                    position: l.position.map(|c| c as f32),
                    color,
                    intensity: l.intensity as f32,
                },
            }
        })
        .collect()
}

/// Every visual shape in a world, with materials, classes and instance ids.
///
/// Built once from the world ([`VisualScene::from_world`]); rebuild it after spawning or
/// removing models. [`VisualScene::world_poses`] reads where every shape is now.
///
/// ```
/// use hearth_sim::sensors::{SemanticClass, VisualScene};
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::Isometry3;
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
/// let scene = VisualScene::from_world(&world);
/// assert_eq!(scene.items.len(), 2); // the ground and the crate
/// assert_eq!(scene.instances[1].name, "crate");
/// assert_eq!(scene.items[0].semantic, SemanticClass::FLOOR);
/// let poses = scene.world_poses(&world);
/// assert!((poses[1].translation.x - 1.0).abs() < 1e-6);
/// ```
#[derive(Clone, Debug, Default)]
pub struct VisualScene {
    /// The shapes.
    pub items: Vec<VisualItem>,
    /// Instances; item `i` belongs to `instances[items[i].instance - 1]`.
    pub instances: Vec<Instance>,
    /// Lights (the world's, or [`default_lights`] when it has none).
    pub lights: Vec<SceneLight>,
}

fn shape_of(geometry: &Geometry) -> VisualShape {
    match geometry {
        Geometry::Box { half_extents } => VisualShape::Box {
            half: [half_extents.x as f32, half_extents.y as f32, half_extents.z as f32],
        },
        Geometry::Cylinder { radius, length } => VisualShape::Cylinder {
            radius: *radius as f32,
            half_length: (*length / 2.0) as f32,
        },
        Geometry::Capsule { radius, length } => VisualShape::Capsule {
            radius: *radius as f32,
            half_length: (*length / 2.0) as f32,
        },
        Geometry::Sphere { radius } => VisualShape::Sphere { radius: *radius as f32 },
        Geometry::Mesh { mesh, .. } => VisualShape::Mesh(Arc::clone(mesh)),
    }
}

fn box_shape(half: [f64; 3]) -> VisualShape {
    VisualShape::Box {
        half: half.map(|h| h as f32),
    }
}

impl VisualScene {
    /// Collects every visual of `world`: static visuals, plain bodies (the ground, building
    /// pieces, boxes: their collider cuboids, in their [`World::body_material`]), then each
    /// model's link visuals. The ground is left out when static floor slabs cover it.
    ///
    /// ```
    /// use hearth_sim::sensors::{SemanticClass, VisualScene};
    /// use hearth_sim::world::{World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// let scene = VisualScene::from_world(&world);
    /// assert_eq!(scene.items.len(), 1); // the ground alone
    /// assert_eq!(scene.instances[0].semantic, SemanticClass::FLOOR);
    /// ```
    pub fn from_world(world: &World) -> Self {
        let mut scene = VisualScene::default();
        let s = &world.state;
        let new_instance = |scene: &mut VisualScene, name: &str, semantic: u32| -> u32 {
            scene.instances.push(Instance {
                name: name.to_owned(),
                semantic,
            });
            scene.instances.len() as u32
        };
        for v in s.static_visuals.iter() {
            let semantic = SemanticClass::of_body_name(&v.name);
            let instance = new_instance(&mut scene, &v.name, semantic);
            scene.items.push(VisualItem {
                body: None,
                local: v.pose,
                shape: box_shape(v.half_extents),
                material: PbrMaterial::of(v.material),
                semantic,
                instance,
            });
        }
        let floors_cover_ground = s.static_visuals.iter().any(|v| v.name.contains("floor/"));
        let model_bodies: std::collections::HashSet<RigidBodyHandle> =
            s.models.iter().flat_map(|m| m.bodies.iter().copied()).collect();
        for (handle, rb) in s.bodies.iter() {
            if model_bodies.contains(&handle) {
                continue;
            }
            if Some(handle) == s.ground && floors_cover_ground {
                continue;
            }
            let name = s.names.get(rb.user_data as usize).map_or("body", String::as_str);
            let semantic = SemanticClass::of_body_name(name);
            let material = s.body_materials.get(rb.user_data as usize).copied().flatten().map_or(
                if semantic == SemanticClass::FLOOR {
                    PbrMaterial::of(Material::Stone)
                } else {
                    PbrMaterial::from_urdf(None, None)
                },
                PbrMaterial::of,
            );
            let instance = new_instance(&mut scene, name, semantic);
            for &ch in rb.colliders() {
                let Some(co) = s.colliders.get(ch) else { continue };
                let Some(cuboid) = co.shape().as_cuboid() else { continue };
                let h = cuboid.half_extents;
                let local = co.position_wrt_parent().map_or(Isometry3::identity(), from_pose);
                scene.items.push(VisualItem {
                    body: Some(handle),
                    local,
                    shape: box_shape([h.x as f64, h.y as f64, h.z as f64]),
                    material,
                    semantic,
                    instance,
                });
            }
        }
        for entry in &s.models {
            let semantic = SemanticClass::of_model(entry.model.name());
            let instance = new_instance(&mut scene, &entry.name, semantic);
            for (li, link) in entry.model.links().iter().enumerate() {
                let (body, link_in_body) = entry.link_bodies[li];
                let link_in_body = from_pose(&link_in_body);
                for v in &link.visuals {
                    scene.items.push(VisualItem {
                        body: Some(body),
                        local: link_in_body * v.origin,
                        shape: shape_of(&v.geometry),
                        material: PbrMaterial::from_urdf(v.material.as_deref(), v.rgba),
                        semantic,
                        instance,
                    });
                }
            }
        }
        scene.lights = if s.lights.is_empty() {
            default_lights()
        } else {
            scene_lights(&s.lights)
        };
        scene
    }

    /// World pose of every item now (same order as `items`).
    ///
    /// ```
    /// # use hearth_sim::sensors::VisualScene;
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
    /// let scene = VisualScene::from_world(&world);
    /// let poses = scene.world_poses(&world);
    /// assert_eq!(poses.len(), scene.items.len());
    /// assert!((poses[1].translation.x - 1.0).abs() < 1e-9);
    /// ```
    pub fn world_poses(&self, world: &World) -> Vec<Isometry3<f64>> {
        let mut out = Vec::with_capacity(self.items.len());
        self.world_poses_into(world, &mut out);
        out
    }

    /// [`VisualScene::world_poses`] into a reused buffer. Items whose body has left the world
    /// keep the identity pose.
    ///
    /// ```
    /// # use hearth_sim::sensors::VisualScene;
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
    /// let scene = VisualScene::from_world(&world);
    /// let mut poses = vec![Isometry3::identity(); 9];
    /// scene.world_poses_into(&world, &mut poses);
    /// assert_eq!(poses.len(), 2);
    /// assert!((poses[1].translation.x - 1.0).abs() < 1e-9);
    /// ```
    pub fn world_poses_into(&self, world: &World, out: &mut Vec<Isometry3<f64>>) {
        out.clear();
        let bodies = &world.state.bodies;
        let mut cached: Option<(RigidBodyHandle, Isometry3<f64>)> = None;
        for item in &self.items {
            let pose = match item.body {
                None => item.local,
                Some(h) => {
                    let body_pose = match cached {
                        Some((ch, p)) if ch == h => p,
                        _ => {
                            let p = bodies
                                .get(h)
                                .map_or(Isometry3::identity(), |rb| from_pose(rb.position()));
                            cached = Some((h, p));
                            p
                        }
                    };
                    body_pose * item.local
                }
            };
            out.push(pose);
        }
    }

    /// Number of triangles a tessellation with `segments` around each round shape has (for
    /// sizing GPU buffers and reports).
    ///
    /// ```
    /// # use hearth_sim::sensors::VisualScene;
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
    /// let scene = VisualScene::from_world(&world);
    /// let ground = scene.triangle_estimate(16) - 12; // the crate is a box: 12 triangles
    /// assert_eq!(scene.triangle_estimate(32), ground + 12);
    /// ```
    pub fn triangle_estimate(&self, segments: usize) -> usize {
        self.items
            .iter()
            .map(|i| match &i.shape {
                VisualShape::Box { .. } => 12,
                VisualShape::Cylinder { .. } => 4 * segments,
                VisualShape::Sphere { .. } | VisualShape::Capsule { .. } => segments * segments,
                VisualShape::Mesh(m) => m.triangles.len(),
            })
            .sum()
    }
}

/// The pose of an isometry's parts as f32 arrays (translation, quaternion xyzw).
///
/// ```
/// use hearth_sim::sensors::pose_f32;
/// use nalgebra::{Isometry3, Vector3};
/// let p = Isometry3::new(Vector3::new(1.0, 2.0, 3.0), Vector3::z() * std::f64::consts::PI);
/// let (t, q) = pose_f32(&p);
/// assert_eq!(t, [1.0, 2.0, 3.0]);
/// assert!((q[2].abs() - 1.0).abs() < 1e-6 && q[3].abs() < 1e-6); // half a turn about z
/// ```
pub fn pose_f32(p: &Isometry3<f64>) -> ([f32; 3], [f32; 4]) {
    let t: Translation3<f64> = p.translation;
    let q: UnitQuaternion<f64> = p.rotation;
    (
        [t.x as f32, t.y as f32, t.z as f32],
        [q.i as f32, q.j as f32, q.k as f32, q.w as f32],
    )
}
