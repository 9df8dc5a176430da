//! [`RaycastCamera`]: a camera that needs no graphics driver. One ray per pixel through the
//! [`RayScene`]; every modality comes straight from the hit (depth, normal, point, ids), flows
//! from re-projecting the hit point with the hit shape's previous pose and the previous camera
//! pose, and RGB from shading the hit's material under the scene's lights.

use nalgebra::Isometry3;
use parry3d::math::{Pose, Vector};
use rayon::prelude::*;

use super::RayScene;
use crate::sensors::camera::{CameraIntrinsics, Frame, Modality, ModalitySet, RenderOptions, check_render_inputs};
use crate::sensors::error::{SensorError, SensorResult};
use crate::sensors::shading::{BACKGROUND_SRGB, LightSample, light_at, shade, to_srgb8};
use crate::sensors::visuals::{PbrMaterial, SceneLight, VisualScene};
use hearth_kinematics::to_pose;

/// Offset (m) of shadow rays off the surface, so a surface does not shadow itself.
const SHADOW_BIAS: f32 = 2e-3;

/// What one pixel's ray found.
#[derive(Clone, Copy, Debug, Default)]
struct Sample {
    /// Item hit, or `u32::MAX`.
    item: u32,
    /// Distance along the unit ray.
    toi: f32,
    /// World normal, facing the camera.
    normal: Vector,
    /// Shaded colour.
    rgb: [u8; 3],
}

const NO_HIT: u32 = u32::MAX;

/// The ray-cast camera backend.
///
/// ```
/// use hearth_sim::sensors::{CameraIntrinsics, Modality, ModalitySet, Mount, RaycastCamera, Frame, VisualScene};
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::{Isometry3, Point3};
///
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), false).unwrap();
/// let scene = VisualScene::from_world(&world);
/// let k = CameraIntrinsics::new(64, 64, 60.0).unwrap();
/// let mut camera = RaycastCamera::new(&scene, k, Default::default()).unwrap();
/// let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap() else { unreachable!() };
/// let mut frame = Frame::default();
/// let set = ModalitySet::EMPTY.with(Modality::Depth);
/// camera.render(&scene.world_poses(&world), &pose, set, &mut frame).unwrap();
/// let centre = frame.depth[frame.index(32, 32)];
/// assert!((centre - 2.5).abs() < 1e-3, "{centre}");
/// ```
#[derive(Debug)]
pub struct RaycastCamera {
    intrinsics: CameraIntrinsics,
    options: RenderOptions,
    rays: RayScene,
    materials: Vec<PbrMaterial>,
    ids: Vec<(u32, u32)>,
    lights: Vec<SceneLight>,
    /// Per pixel: unit ray direction in the camera frame.
    dirs: Vec<Vector>,
    samples: Vec<Sample>,
    prev_camera: Option<Pose>,
}

impl RaycastCamera {
    /// A camera over `scene` (its shapes, materials, ids and lights).
    ///
    /// # Errors
    /// [`SensorError::InvalidResolution`] / [`SensorError::InvalidParameter`] for bad intrinsics.
    ///
    /// ```
    /// use hearth_sim::sensors::{CameraIntrinsics, Preset, RaycastCamera, RenderOptions, VisualScene};
    /// let k = CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// let camera = RaycastCamera::new(&VisualScene::default(), k, RenderOptions::from(Preset::VisualRl)).unwrap();
    /// assert_eq!(camera.intrinsics(), &k);
    /// ```
    pub fn new(scene: &VisualScene, intrinsics: CameraIntrinsics, options: RenderOptions) -> SensorResult<Self> {
        intrinsics.validate()?;
        let (w, h) = (intrinsics.width, intrinsics.height);
        let mut dirs = Vec::with_capacity(intrinsics.pixels());
        for v in 0..h {
            for u in 0..w {
                let d = intrinsics.pixel_ray(u as f64, v as f64).normalize();
                dirs.push(Vector::new(d.x as f32, d.y as f32, d.z as f32));
            }
        }
        Ok(Self {
            intrinsics,
            options,
            rays: RayScene::new(scene),
            materials: scene.items.iter().map(|i| i.material).collect(),
            ids: scene.items.iter().map(|i| (i.semantic, i.instance)).collect(),
            lights: scene.lights.clone(),
            dirs,
            samples: vec![Sample::default(); intrinsics.pixels()],
            prev_camera: None,
        })
    }

    /// The intrinsics.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, Modality, ModalitySet, Mount, Preset, RaycastCamera, RenderOptions, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), false).unwrap();
    /// # let scene = VisualScene::from_world(&world);
    /// # let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap() else { unreachable!() };
    /// let k = CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// let mut camera = RaycastCamera::new(&scene, k, RenderOptions::from(Preset::VisualRl)).unwrap();
    /// assert_eq!(camera.intrinsics().pixels(), 32 * 24);
    /// ```
    pub fn intrinsics(&self) -> &CameraIntrinsics {
        &self.intrinsics
    }

    /// Changes one item's material (material randomisation).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for an item index out of range.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, Modality, ModalitySet, Mount, Preset, RaycastCamera, RenderOptions, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), false).unwrap();
    /// # let scene = VisualScene::from_world(&world);
    /// # let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap() else { unreachable!() };
    /// let k = CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// let mut camera = RaycastCamera::new(&scene, k, RenderOptions::from(Preset::VisualRl)).unwrap();
    /// use hearth_sim::sensors::PbrMaterial;
    /// let rgb = ModalitySet::EMPTY.with(Modality::Rgb);
    /// let (mut before, mut after) = (Frame::default(), Frame::default());
    /// camera.render(&scene.world_poses(&world), &pose, rgb, &mut before).unwrap();
    /// let red = PbrMaterial { base_color: [1.0, 0.0, 0.0, 1.0], ..scene.items[1].material };
    /// camera.set_material(1, red).unwrap(); // the crate
    /// camera.render(&scene.world_poses(&world), &pose, rgb, &mut after).unwrap();
    /// let i = 3 * after.index(16, 12);
    /// assert!(after.rgb[i] > after.rgb[i + 1] && before.rgb[i..i + 3] != after.rgb[i..i + 3]);
    /// assert!(camera.set_material(2, red).is_err()); // two items only
    /// ```
    pub fn set_material(&mut self, item: usize, material: PbrMaterial) -> SensorResult<()> {
        let n = self.materials.len();
        let slot = self.materials.get_mut(item).ok_or(SensorError::InvalidParameter {
            name: "item",
            value: item as f64,
            reason: if n == 0 {
                "the scene has no items"
            } else {
                "must index a scene item"
            },
        })?;
        *slot = material;
        Ok(())
    }

    /// Forgets the previous frame: the next flows are 0.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, Modality, ModalitySet, Mount, Preset, RaycastCamera, RenderOptions, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), false).unwrap();
    /// # let scene = VisualScene::from_world(&world);
    /// # let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap() else { unreachable!() };
    /// let k = CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// let mut camera = RaycastCamera::new(&scene, k, RenderOptions::from(Preset::VisualRl)).unwrap();
    /// let flow = ModalitySet::EMPTY.with(Modality::OpticalFlow);
    /// let mut frame = Frame::default();
    /// let poses = scene.world_poses(&world);
    /// camera.render(&poses, &pose, flow, &mut frame).unwrap();
    /// let moved = Isometry3::translation(0.0, 0.3, 0.0) * pose;
    /// camera.reset_flow();
    /// camera.render(&poses, &moved, flow, &mut frame).unwrap();
    /// assert!(frame.optical_flow.iter().all(|f| *f == [0.0; 2])); // no previous frame
    /// ```
    pub fn reset_flow(&mut self) {
        self.prev_camera = None;
    }

    /// Renders `modalities` into `frame` with the items at `item_poses` (one world pose per
    /// scene item) and the optical frame at `camera`.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when `item_poses` has the wrong length or `camera` is
    /// not finite.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, Modality, ModalitySet, Mount, Preset, RaycastCamera, RenderOptions, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), false).unwrap();
    /// # let scene = VisualScene::from_world(&world);
    /// # let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap() else { unreachable!() };
    /// let k = CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// let mut camera = RaycastCamera::new(&scene, k, RenderOptions::from(Preset::VisualRl)).unwrap();
    /// let mut frame = Frame::default();
    /// let set = ModalitySet::EMPTY.with(Modality::Depth).with(Modality::Seg);
    /// camera.render(&scene.world_poses(&world), &pose, set, &mut frame).unwrap();
    /// assert!((frame.depth[frame.index(16, 12)] - 2.5).abs() < 1e-3);
    /// assert_eq!(frame.seg[frame.index(16, 12)], scene.items[1].semantic);
    /// assert!(camera.render(&[], &pose, set, &mut frame).is_err()); // one pose per item needed
    /// ```
    pub fn render(
        &mut self,
        item_poses: &[Isometry3<f64>],
        camera: &Isometry3<f64>,
        modalities: ModalitySet,
        frame: &mut Frame,
    ) -> SensorResult<()> {
        check_render_inputs(item_poses, self.materials.len(), camera)?;
        let cam = to_pose(camera);
        self.rays.update_from_poses(item_poses);
        let k = self.intrinsics;
        frame.prepare(k.width, k.height, modalities);
        self.cast_all(&cam, modalities.contains(Modality::Rgb));

        let prev_cam = self.prev_camera.unwrap_or(cam);
        let cam_inv = cam.inverse();
        let prev_inv = prev_cam.inverse();
        let (near, far) = (k.near as f32, k.far as f32);
        let (fx, fy) = (k.fx() as f32, k.fy() as f32);
        let (cx, cy) = k.principal_point();
        let (cx, cy) = (cx as f32, cy as f32);
        let project = |p: Vector| Vector::new(fx * p.x / p.z + cx, fy * p.y / p.z + cy, 0.0);
        let want = |m| modalities.contains(m);
        let flows = want(Modality::OpticalFlow) || want(Modality::SceneFlow);
        for (i, s) in self.samples.iter().enumerate() {
            let dir = self.dirs[i];
            let p_cam = dir * s.toi;
            let seen = s.item != NO_HIT && p_cam.z >= near && p_cam.z <= far;
            if want(Modality::Rgb) {
                let c = if seen { s.rgb } else { BACKGROUND_SRGB };
                frame.rgb[3 * i..3 * i + 3].copy_from_slice(&c);
            }
            if want(Modality::Depth) {
                frame.depth[i] = if seen { p_cam.z } else { 0.0 };
            }
            if want(Modality::Pc) {
                frame.pc[i] = if seen { p_cam.into() } else { [0.0; 3] };
            }
            if want(Modality::Normal) {
                frame.normal[i] = if seen {
                    (cam.rotation.inverse() * s.normal).into()
                } else {
                    [0.0; 3]
                };
            }
            let (sem, ins) = if seen { self.ids[s.item as usize] } else { (0, 0) };
            if want(Modality::Seg) {
                frame.seg[i] = sem;
            }
            if want(Modality::InsSeg) {
                frame.ins_seg[i] = ins;
            }
            if flows {
                let (mut of, mut sf) = ([0.0f32; 2], [0.0f32; 3]);
                if seen {
                    // The same material point one frame ago, in the previous camera frame.
                    let p_world = cam * p_cam;
                    let local = self.rays.pose(s.item).inverse() * p_world;
                    let prev_world = *self.rays.prev_pose(s.item) * local;
                    let prev_cam_p = prev_inv * prev_world;
                    let now_cam_p = cam_inv * p_world;
                    sf = (now_cam_p - prev_cam_p).into();
                    if prev_cam_p.z > 1e-6 {
                        let d = project(now_cam_p) - project(prev_cam_p);
                        of = [d.x, d.y];
                    }
                }
                if want(Modality::OpticalFlow) {
                    frame.optical_flow[i] = of;
                }
                if want(Modality::SceneFlow) {
                    frame.scene_flow[i] = sf;
                }
            }
        }
        self.prev_camera = Some(cam);
        Ok(())
    }

    /// Casts every pixel's ray (in parallel by rows) and shades hits when `rgb`.
    fn cast_all(&mut self, cam: &Pose, rgb: bool) {
        let width = self.intrinsics.width as usize;
        let k = self.intrinsics;
        let rays = &self.rays;
        let dirs = &self.dirs;
        let materials = &self.materials;
        let lights = &self.lights;
        let options = self.options;
        let origin = cam.translation;
        let init = || Vec::<LightSample>::with_capacity(lights.len());
        self.samples
            .par_chunks_mut(width)
            .enumerate()
            .for_each_init(init, |light_buf, (row, out)| {
                for (col, s) in out.iter_mut().enumerate() {
                    let d_cam = dirs[row * width + col];
                    let dir = cam.rotation * d_cam;
                    let max_toi = k.far as f32 / d_cam.z.max(1e-6);
                    *s = match rays.cast(origin, dir, max_toi) {
                        None => Sample {
                            item: NO_HIT,
                            ..Sample::default()
                        },
                        Some(hit) => {
                            let mut sample = Sample {
                                item: hit.item,
                                toi: hit.toi,
                                normal: hit.normal,
                                rgb: [0; 3],
                            };
                            if rgb {
                                let p = origin + dir * hit.toi;
                                light_buf.clear();
                                for light in lights {
                                    let l = light_at(light, p);
                                    if options.shadows && l.to_light.dot(hit.normal) > 0.0 {
                                        let start = p + hit.normal * SHADOW_BIAS;
                                        let reach = if l.distance.is_finite() {
                                            l.distance - SHADOW_BIAS
                                        } else {
                                            1e3
                                        };
                                        if rays.cast(start, l.to_light, reach).is_some() {
                                            continue;
                                        }
                                    }
                                    light_buf.push(l);
                                }
                                let radiance =
                                    shade(&materials[hit.item as usize], hit.normal, -dir, light_buf, options.pbr);
                                sample.rgb = to_srgb8(radiance);
                            }
                            sample
                        }
                    };
                }
            });
    }
}
