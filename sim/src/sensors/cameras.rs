//! [`Camera`]: a camera in the world, on a robot link or free, rendered by the wgpu backend,
//! the ray caster or the CPU depth rasteriser (chosen by [`Backend`]; `auto` takes wgpu when an
//! adapter exists).

use nalgebra::Isometry3;

use super::camera::{Backend, CameraIntrinsics, Frame, ModalitySet, Mount, Preset, RenderOptions};
use super::error::{SensorError, SensorResult};
use super::gpu::{GpuCamera, gpu_adapter};
use super::raster::RasterCamera;
use super::raycast::RaycastCamera;
use super::visuals::{PbrMaterial, VisualScene};
use crate::world::{ModelHandle, World};

/// How to build a [`Camera`].
///
/// ```
/// use hearth_sim::sensors::{Backend, CameraConfig, Preset};
/// let c = CameraConfig::preset(Preset::VisualRl).unwrap();
/// assert_eq!(c.intrinsics.width, 128);
/// assert_eq!(c.backend, Backend::Auto);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct CameraConfig {
    /// Image size, field of view and clipping.
    pub intrinsics: CameraIntrinsics,
    /// Shading, shadows, MSAA.
    pub options: RenderOptions,
    /// Which implementation renders.
    pub backend: Backend,
    /// Where the camera sits (`None`: the robot's default camera link).
    pub mount: Option<Mount>,
}

impl CameraConfig {
    /// A preset's resolution and options, 90° vertical field of view (iGibson's default),
    /// automatic backend, the robot's default camera.
    ///
    /// # Errors
    /// Never for the built-in presets; kept fallible for symmetry with custom intrinsics.
    ///
    /// ```
    /// use hearth_sim::sensors::{CameraConfig, Preset};
    /// let c = CameraConfig::preset(Preset::HighFidelity).unwrap();
    /// assert_eq!((c.intrinsics.width, c.intrinsics.vfov_deg), (512, 90.0));
    /// assert!(c.mount.is_none() && c.options.shadows);
    /// ```
    pub fn preset(preset: Preset) -> SensorResult<Self> {
        Ok(Self {
            intrinsics: preset.intrinsics(90.0)?,
            options: preset.into(),
            backend: Backend::Auto,
            mount: None,
        })
    }
}

/// The two implementations behind one interface.
enum Renderer {
    Gpu(Box<GpuCamera>),
    Ray(Box<RaycastCamera>),
    Raster(Box<RasterCamera>),
}

/// A camera reading the live world: every visual shape, posed from physics at each
/// [`Camera::render`].
///
/// ```
/// use hearth_sim::sensors::{Backend, Camera, CameraConfig, Modality, ModalitySet, Mount, Preset};
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::{Isometry3, Point3};
///
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
/// let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
/// config.backend = Backend::Raycast;
/// config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
/// let mut camera = Camera::new(&world, None, config).unwrap();
/// let frame = camera.render(&world, ModalitySet::EMPTY.with(Modality::Depth)).unwrap();
/// assert!((frame.depth[frame.index(64, 64)] - 2.5).abs() < 0.01);
/// ```
pub struct Camera {
    renderer: Renderer,
    scene: VisualScene,
    mount: Mount,
    robot: Option<ModelHandle>,
    config: CameraConfig,
    poses: Vec<Isometry3<f64>>,
    frame: Frame,
}

impl std::fmt::Debug for Camera {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Camera")
            .field("backend", &self.backend())
            .field("mount", &self.mount)
            .field("intrinsics", &self.config.intrinsics)
            .finish_non_exhaustive()
    }
}

impl Camera {
    /// A camera on `robot` (at `config.mount`, or the robot's default camera link) or free
    /// (`config.mount = Some(Mount::Free(..))`, `robot` may be `None`).
    ///
    /// # Errors
    /// Bad intrinsics; [`SensorError::NoDefaultMount`] / [`SensorError::NoSuchLink`] for a
    /// mount the robot lacks; [`SensorError::NoAdapter`] for [`Backend::Wgpu`] without a
    /// graphics adapter; [`SensorError::World`] for an unknown robot.
    ///
    /// ```
    /// use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Mount, Preset, SensorError};
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// config.backend = Backend::Raycast;
    /// // No robot and no mount: nowhere to put the camera.
    /// assert!(matches!(Camera::new(&world, None, config.clone()), Err(SensorError::NoDefaultMount { .. })));
    /// config.mount = Some(Mount::Free(Isometry3::translation(0.0, 0.0, 1.0)));
    /// assert!(Camera::new(&world, None, config).is_ok());
    /// ```
    pub fn new(world: &World, robot: Option<ModelHandle>, config: CameraConfig) -> SensorResult<Self> {
        config.intrinsics.validate()?;
        let mount = match (&config.mount, robot) {
            (Some(m), _) => m.clone(),
            (None, Some(r)) => {
                let name = world.model(r)?.name().to_owned();
                Mount::default_camera(&name).ok_or(SensorError::NoDefaultMount {
                    robot: name,
                    sensor: "camera",
                })?
            }
            (None, None) => {
                return Err(SensorError::NoDefaultMount {
                    robot: "(none)".into(),
                    sensor: "camera",
                });
            }
        };
        // Fails now, not at the first frame, when the link is missing.
        mount.pose(world, robot)?;
        let scene = VisualScene::from_world(world);
        let renderer = Self::make_renderer(&scene, &config)?;
        Ok(Self {
            renderer,
            scene,
            mount,
            robot,
            config,
            poses: Vec::new(),
            frame: Frame::default(),
        })
    }

    fn make_renderer(scene: &VisualScene, config: &CameraConfig) -> SensorResult<Renderer> {
        let ray = || -> SensorResult<Renderer> {
            Ok(Renderer::Ray(Box::new(RaycastCamera::new(
                scene,
                config.intrinsics,
                config.options,
            )?)))
        };
        let gpu = || -> SensorResult<Renderer> {
            Ok(Renderer::Gpu(Box::new(GpuCamera::new(
                scene,
                config.intrinsics,
                config.options,
            )?)))
        };
        match config.backend {
            Backend::Raycast => ray(),
            Backend::Raster => Ok(Renderer::Raster(Box::new(RasterCamera::new(scene, config.intrinsics)?))),
            Backend::Wgpu => gpu(),
            Backend::Auto => match gpu_adapter() {
                Ok(_) => match gpu() {
                    Ok(r) => Ok(r),
                    Err(SensorError::NoAdapter { reason }) | Err(SensorError::Gpu(reason)) => {
                        eprintln!("hearth: wgpu camera unavailable ({reason}); using the ray-cast camera");
                        ray()
                    }
                    Err(e) => Err(e),
                },
                Err(reason) => {
                    eprintln!("hearth: no graphics adapter ({reason}); using the ray-cast camera");
                    ray()
                }
            },
        }
    }

    /// The backend in use ([`Backend::Wgpu`], [`Backend::Raycast`] or [`Backend::Raster`]).
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// assert_eq!(camera.backend(), Backend::Raycast);
    /// ```
    pub fn backend(&self) -> Backend {
        match self.renderer {
            Renderer::Gpu(_) => Backend::Wgpu,
            Renderer::Ray(_) => Backend::Raycast,
            Renderer::Raster(_) => Backend::Raster,
        }
    }

    /// The graphics adapter's name for the wgpu backend; `cpu ray casting` or `cpu rasteriser`
    /// for the CPU backends.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// assert_eq!(camera.adapter(), "cpu ray casting");
    /// ```
    pub fn adapter(&self) -> &str {
        match &self.renderer {
            Renderer::Gpu(g) => g.adapter_name(),
            Renderer::Ray(_) => "cpu ray casting",
            Renderer::Raster(_) => "cpu rasteriser",
        }
    }

    /// The configuration.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// assert_eq!(camera.config().intrinsics.width, 32);
    /// ```
    pub fn config(&self) -> &CameraConfig {
        &self.config
    }

    /// The visual scene the camera draws.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// let scene = camera.scene();
    /// assert_eq!(scene.items.len(), 2); // the ground and the crate
    /// assert_eq!(scene.instances[1].name, "crate");
    /// ```
    pub fn scene(&self) -> &VisualScene {
        &self.scene
    }

    /// The world pose of the camera's optical frame now.
    ///
    /// # Errors
    /// As [`Mount::pose`].
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// let pose = camera.pose(&world).unwrap();
    /// assert_eq!(pose.translation.vector.z, 0.5);
    /// ```
    pub fn pose(&self, world: &World) -> SensorResult<Isometry3<f64>> {
        self.mount.pose(world, self.robot)
    }

    /// Renders `modalities` of the world as it is now and returns the frame.
    ///
    /// # Errors
    /// [`SensorError::Gpu`] when the device fails; mount errors if the robot left the world.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// let frame = camera.render(&world, ModalitySet::EMPTY.with(Modality::InsSeg)).unwrap();
    /// assert_eq!((frame.width, frame.height), (32, 24));
    /// assert_eq!(frame.ins_seg[frame.index(16, 12)], 2); // the crate, instance 2
    /// ```
    pub fn render(&mut self, world: &World, modalities: ModalitySet) -> SensorResult<&Frame> {
        let pose = self.mount.pose(world, self.robot)?;
        self.render_from(world, &pose, modalities)
    }

    /// Renders from an explicit optical-frame pose (ignoring the mount).
    ///
    /// # Errors
    /// As [`Camera::render`], and [`SensorError::InvalidParameter`] for a non-finite pose.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// // Look away from the crate, straight down at the ground from 2 m up.
    /// let down = Mount::look_at(Point3::new(0.0, 0.0, 2.0), Point3::new(0.0, 0.0, 0.0)).unwrap();
    /// let Mount::Free(pose) = down else { unreachable!() };
    /// let frame = camera.render_from(&world, &pose, ModalitySet::EMPTY.with(Modality::Depth)).unwrap();
    /// assert!((frame.depth[frame.index(16, 12)] - 2.0).abs() < 0.01);
    /// ```
    pub fn render_from(
        &mut self,
        world: &World,
        pose: &Isometry3<f64>,
        modalities: ModalitySet,
    ) -> SensorResult<&Frame> {
        self.scene.world_poses_into(world, &mut self.poses);
        match &mut self.renderer {
            Renderer::Gpu(g) => g.render(&self.poses, pose, modalities, &mut self.frame)?,
            Renderer::Ray(r) => r.render(&self.poses, pose, modalities, &mut self.frame)?,
            Renderer::Raster(r) => r.render(&self.poses, pose, modalities, &mut self.frame)?,
        }
        Ok(&self.frame)
    }

    /// The last frame rendered.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// assert!(camera.frame().depth.is_empty()); // nothing rendered yet
    /// camera.render(&world, ModalitySet::EMPTY.with(Modality::Depth)).unwrap();
    /// assert_eq!(camera.frame().depth.len(), 32 * 24);
    /// ```
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Changes the material of scene item `item` (visual material randomisation).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for an item out of range.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// use hearth_sim::{assets::Material, sensors::PbrMaterial};
    /// camera.set_material(1, PbrMaterial::of(Material::Metal)).unwrap();
    /// assert_eq!(camera.scene().items[1].material.metallic, 1.0);
    /// assert!(camera.set_material(99, PbrMaterial::of(Material::Wood)).is_err());
    /// ```
    pub fn set_material(&mut self, item: usize, material: PbrMaterial) -> SensorResult<()> {
        match &mut self.renderer {
            Renderer::Gpu(g) => g.set_material(item, material)?,
            Renderer::Ray(r) => r.set_material(item, material)?,
            // Materials do not change depth or ids.
            Renderer::Raster(_) => {
                if item >= self.scene.items.len() {
                    return Err(SensorError::InvalidParameter {
                        name: "item",
                        value: item as f64,
                        reason: "must index a scene item",
                    });
                }
            }
        }
        self.scene.items[item].material = material;
        Ok(())
    }

    /// Forgets the previous frame: the next flows are 0 (call after a reset or teleport).
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// let flow = ModalitySet::EMPTY.with(Modality::SceneFlow);
    /// camera.render(&world, flow).unwrap();
    /// camera.reset_flow();
    /// let frame = camera.render(&world, flow).unwrap();
    /// assert!(frame.scene_flow.iter().all(|f| *f == [0.0; 3]));
    /// ```
    pub fn reset_flow(&mut self) {
        match &mut self.renderer {
            Renderer::Gpu(g) => g.reset_flow(),
            Renderer::Ray(r) => r.reset_flow(),
            Renderer::Raster(_) => {}
        }
    }

    /// Re-reads the world's visuals (after spawning or removing models) and rebuilds the
    /// renderer with the same configuration.
    ///
    /// # Errors
    /// As [`Camera::new`].
    ///
    /// ```
    /// # use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, Modality, ModalitySet, Mount, Preset};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), true).unwrap();
    /// # let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// # config.intrinsics = CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// # config.backend = Backend::Raycast;
    /// # config.mount = Some(Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap());
    /// # let mut camera = Camera::new(&world, None, config).unwrap();
    /// world.add_box("box", [0.1; 3], &Isometry3::translation(1.0, 0.0, 0.1), true).unwrap();
    /// assert_eq!(camera.scene().items.len(), 2);
    /// camera.rebuild(&world).unwrap();
    /// assert_eq!(camera.scene().items.len(), 3);
    /// ```
    pub fn rebuild(&mut self, world: &World) -> SensorResult<()> {
        let scene = VisualScene::from_world(world);
        let renderer = Self::make_renderer(&scene, &self.config)?;
        self.scene = scene;
        self.renderer = renderer;
        Ok(())
    }
}
