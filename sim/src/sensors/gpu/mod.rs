//! The wgpu camera backend: a headless rasteriser producing every [`Modality`] of a
//! [`VisualScene`] (on a GPU, or on a CPU through Mesa's lavapipe Vulkan driver).
//!
//! - The scene is tessellated once into one vertex and index buffer; each vertex carries the
//!   index of its item, whose current and previous model-view transforms live in a storage
//!   buffer rewritten each frame. The scene is drawn in a few draw calls (items outside the
//!   view frustum are skipped on the CPU; closed shapes are drawn with back-face culling,
//!   meshes without).
//! - One geometry pass writes every requested output at once into separate colour targets:
//!   tone-mapped colour (sRGB RGBA8), camera-frame z (R32Float), normals (RGBA16Float),
//!   semantic and instance ids (RG32Uint, flat), scene flow (RGBA32Float) and optical flow
//!   (RG32Float). The shader is specialised to the requested outputs, and only those are copied
//!   back. `pc` is computed on the CPU from depth and each pixel's ray.
//! - Colour is physically based when [`RenderOptions::pbr`] is on (metallic-roughness,
//!   Cook-Torrance GGX specular and Lambert diffuse, the first 8 lights of
//!   [`VisualScene::lights`] (point lights fall off as 1/d², without shadows), an
//!   image-based ambient term from a sky/ground dome with a split-sum specular approximation),
//!   Lambert otherwise; then exposure, ACES tone mapping and sRGB encoding. Background is the
//!   sky colour [`GpuCamera::SKY_RGB`].
//! - Colour passes are preceded by a depth-only pre-pass, so each pixel is shaded once.
//! - With [`RenderOptions::shadows`] the first directional light casts shadows (an
//!   orthographic 1024² shadow map over the scene within 15 m of the camera, 2×2 PCF by a filtering
//!   comparison sampler; re-rendered only when the camera or an item moved).
//! - With [`RenderOptions::msaa`] = 4, colour is rendered in its own 4× multisampled pass and
//!   resolved; depth, normals, ids, flows and `pc` always come from a single-sampled pass, so
//!   they never blend two surfaces.
//!
//! Depth uses a reversed (near = 1, far = 0) 32-bit float buffer; the `depth` modality is the
//! linear camera-frame z written by the fragment shader, not the buffer value.

mod pipeline;
pub(crate) mod tessellate;

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use nalgebra::{Isometry3, Matrix4, Vector3};
use wgpu::util::DeviceExt;

use super::camera::{CameraIntrinsics, Frame, Modality, ModalitySet, RenderOptions};
use super::error::{SensorError, SensorResult};
use super::visuals::{PbrMaterial, SceneLight, VisualScene};
use pipeline::{PipelineKey, Target};
use tessellate::ItemRange;

/// Most lights the shader evaluates (the first ones of the scene).
const MAX_LIGHTS: usize = 8;
/// Exposure: scene radiance is multiplied by this before tone mapping.
const EXPOSURE: f32 = 0.1;
/// Radiance of the ambient sky above and of the ground below (linear RGB).
const SKY_RADIANCE: [f32; 3] = [1.1, 1.2, 1.35];
const GROUND_RADIANCE: [f32; 3] = [0.45, 0.4, 0.36];
/// Side of the shadow map in texels.
const SHADOW_MAP_SIZE: u32 = 1024;
/// Farthest camera depth (m) the shadow map covers.
const SHADOW_RANGE: f64 = 15.0;
/// Floats per item in the transform buffer (current and previous 3×4 model-view).
const XF_FLOATS: usize = 24;
/// Rows of the copy-to-buffer must be aligned to this many bytes.
const ROW_ALIGN: u32 = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct LightGpu {
    pos: [f32; 4],
    color: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct CameraGpu {
    proj: [f32; 4],
    pix: [f32; 4],
    up: [f32; 4],
    sky: [f32; 4],
    ground: [f32; 4],
    shadow: [[f32; 4]; 4],
    counts: [u32; 4],
    lights: [LightGpu; MAX_LIGHTS],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct MaterialGpu {
    color: [f32; 4],
    metallic: f32,
    roughness: f32,
    semantic: u32,
    instance: u32,
}

impl MaterialGpu {
    fn new(m: &PbrMaterial, semantic: u32, instance: u32) -> Self {
        Self {
            color: m
                .base_color
                .map(|c| if c.is_finite() { c.clamp(0.0, 1.0) } else { 0.0 }),
            metallic: if m.metallic.is_finite() {
                m.metallic.clamp(0.0, 1.0)
            } else {
                0.0
            },
            roughness: if m.roughness.is_finite() {
                m.roughness.clamp(0.04, 1.0)
            } else {
                1.0
            },
            semantic,
            instance,
        }
    }
}

fn new_instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    desc.flags = wgpu::InstanceFlags::empty().with_env();
    wgpu::Instance::new(desc)
}

fn request_adapter(instance: &wgpu::Instance) -> Result<wgpu::Adapter, String> {
    let mut options = wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::default(),
        force_fallback_adapter: false,
        compatible_surface: None,
        apply_limit_buckets: false,
    };
    match pollster::block_on(instance.request_adapter(&options)) {
        Ok(a) => Ok(a),
        Err(first) => {
            options.force_fallback_adapter = true;
            pollster::block_on(instance.request_adapter(&options))
                .map_err(|second| format!("{first}; with a fallback adapter: {second}"))
        }
    }
}

fn panic_message(p: Box<dyn std::any::Any + Send>) -> String {
    p.downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".to_owned())
}

/// Name of the adapter wgpu picks (headless, no surface, Vulkan), or why there is none.
///
/// The answer is computed once per process and cached.
///
/// ```
/// match hearth_sim::sensors::gpu_adapter() {
///     Ok(name) => assert!(!name.is_empty()),
///     Err(why) => eprintln!("no adapter: {why}"),
/// }
/// ```
pub fn gpu_adapter() -> Result<String, String> {
    static ADAPTER: OnceLock<Result<String, String>> = OnceLock::new();
    ADAPTER
        .get_or_init(|| {
            std::panic::catch_unwind(|| {
                let instance = new_instance();
                request_adapter(&instance).map(|a| a.get_info().name)
            })
            .unwrap_or_else(|p| Err(panic_message(p)))
        })
        .clone()
}

/// A device with its queue and the errors it reported.
struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    name: String,
    limits: wgpu::Limits,
    errors: Arc<Mutex<Vec<String>>>,
}

impl Gpu {
    fn open() -> SensorResult<Self> {
        let opened = std::panic::catch_unwind(|| -> Result<Gpu, String> {
            let instance = new_instance();
            let adapter = request_adapter(&instance)?;
            let name = adapter.get_info().name;
            let limits = adapter.limits();
            let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
                label: Some("hearth camera"),
                required_features: wgpu::Features::empty(),
                required_limits: limits.clone(),
                experimental_features: Default::default(),
                memory_hints: wgpu::MemoryHints::Performance,
                trace: Default::default(),
            }))
            .map_err(|e| format!("adapter `{name}` refused a device: {e}"))?;
            let errors = Arc::new(Mutex::new(Vec::new()));
            let sink = Arc::clone(&errors);
            device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                sink.lock().unwrap_or_else(|p| p.into_inner()).push(e.to_string());
            }));
            Ok(Gpu {
                device,
                queue,
                name,
                limits,
                errors,
            })
        });
        match opened {
            Ok(Ok(gpu)) => Ok(gpu),
            Ok(Err(reason)) => Err(SensorError::NoAdapter { reason }),
            Err(p) => Err(SensorError::NoAdapter {
                reason: panic_message(p),
            }),
        }
    }

    /// Errors reported since the last check, as one [`SensorError::Gpu`].
    fn check(&self) -> SensorResult<()> {
        let mut errors = self.errors.lock().unwrap_or_else(|p| p.into_inner());
        if errors.is_empty() {
            return Ok(());
        }
        let msg = errors.join("; ");
        errors.clear();
        Err(SensorError::Gpu(msg))
    }
}

/// Where a staging buffer's map callback leaves its result.
type MapSlot = Arc<Mutex<Option<Result<(), wgpu::BufferAsyncError>>>>;

/// A colour target and the buffer it is copied back through.
struct TargetTex {
    view: wgpu::TextureView,
    texture: wgpu::Texture,
    /// 4× multisampled colour (RGB with MSAA only).
    msaa_view: Option<wgpu::TextureView>,
    staging: wgpu::Buffer,
    padded_row: u32,
}

/// Shadow-map resources.
struct Shadow {
    view: wgpu::TextureView,
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    lxf_buf: wgpu::Buffer,
    /// Light-space transforms last drawn into the map (empty: none yet).
    last: Vec<[f32; 4]>,
    /// Index of the light that casts shadows.
    light: usize,
}

/// A headless wgpu camera over a [`VisualScene`].
///
/// ```
/// use hearth_sim::sensors::{
///     CameraIntrinsics, Frame, GpuCamera, Modality, ModalitySet, Mount, RenderOptions, VisualScene,
/// };
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::{Isometry3, Point3};
///
/// if hearth_sim::sensors::gpu_adapter().is_err() {
///     return; // no graphics adapter here
/// }
/// let mut world = World::new(WorldConfig { ground_plane: false, ..Default::default() }).unwrap();
/// world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 1.0), false).unwrap();
/// let scene = VisualScene::from_world(&world);
/// let k = CameraIntrinsics::new(64, 64, 60.0).unwrap();
/// let mut cam = GpuCamera::new(&scene, k, RenderOptions::default()).unwrap();
/// let Mount::Free(eye) = Mount::look_at(Point3::new(0.0, 0.0, 1.0), Point3::new(3.0, 0.0, 1.0)).unwrap()
/// else { unreachable!() };
/// let mut frame = Frame::default();
/// let set = ModalitySet::EMPTY.with(Modality::Depth).with(Modality::InsSeg);
/// cam.render(&scene.world_poses(&world), &eye, set, &mut frame).unwrap();
/// let centre = frame.index(32, 32);
/// assert!((frame.depth[centre] - 2.5).abs() < 0.01);
/// assert_eq!(frame.ins_seg[centre], 1);
/// assert_eq!(frame.depth[0], 0.0); // nothing in the corner
/// ```
pub struct GpuCamera {
    gpu: Gpu,
    intrinsics: CameraIntrinsics,
    options: RenderOptions,
    /// Per item: index range in the reordered index buffer and bounding sphere.
    ranges: Vec<ItemRange>,
    /// Draw order: closed items, then open meshes.
    order: Vec<usize>,
    vertex_buf: wgpu::Buffer,
    index_buf: wgpu::Buffer,
    xf_buf: wgpu::Buffer,
    xf: Vec<[f32; 4]>,
    materials: Vec<MaterialGpu>,
    material_buf: wgpu::Buffer,
    camera_buf: wgpu::Buffer,
    lights: Vec<SceneLight>,
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
    pipelines: HashMap<PipelineKey, wgpu::RenderPipeline>,
    targets: HashMap<Target, TargetTex>,
    depth_view: Option<wgpu::TextureView>,
    msaa_depth_view: Option<wgpu::TextureView>,
    shadow: Option<Shadow>,
    /// Visible index runs (start, end, closed), reused.
    runs: Vec<(u32, u32, bool)>,
    /// Per item: whether it is in the view frustum this frame (reused).
    visible: Vec<bool>,
    /// Previous item poses and camera pose (None: the next flows are 0).
    prev_poses: Vec<Isometry3<f64>>,
    prev_camera: Option<Isometry3<f64>>,
    /// Map results of the staging buffers, reused.
    map_results: Vec<MapSlot>,
}

impl std::fmt::Debug for GpuCamera {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuCamera")
            .field("adapter", &self.gpu.name)
            .field("intrinsics", &self.intrinsics)
            .field("options", &self.options)
            .field("items", &self.ranges.len())
            .finish_non_exhaustive()
    }
}

fn rows3(m: &Matrix4<f64>) -> [[f32; 4]; 3] {
    let r = |i: usize| [m[(i, 0)] as f32, m[(i, 1)] as f32, m[(i, 2)] as f32, m[(i, 3)] as f32];
    [r(0), r(1), r(2)]
}

fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// An IEEE half-precision float (as read back from an `Rgba16Float` target) widened to f32,
/// exactly, by moving its bits: a read-back 512² normal image converts 786,432 of them.
fn f16_to_f32(h: u16) -> f32 {
    let sign = u32::from(h & 0x8000) << 16;
    let exp = u32::from((h >> 10) & 0x1f);
    let man = u32::from(h & 0x3ff);
    match exp {
        // Zero and subnormals: man × 2⁻²⁴, exact in f32.
        0 => {
            let v = man as f32 * (1.0 / 16_777_216.0);
            if sign == 0 { v } else { -v }
        }
        // Infinity and NaN keep their payload.
        31 => f32::from_bits(sign | 0x7f80_0000 | (man << 13)),
        // Normal numbers: rebias the exponent from 15 to 127.
        _ => f32::from_bits(sign | ((exp + 112) << 23) | (man << 13)),
    }
}

/// The light-clip transform of a directional light travelling along `direction`: x and y
/// cover the sphere (`centre`, `radius`), z (0 near the light, 1 far) spans `[dmin, dmax]`
/// along the direction, measured from `centre`.
fn light_matrix(direction: Vector3<f64>, centre: Vector3<f64>, radius: f64, dmin: f64, dmax: f64) -> Matrix4<f64> {
    let fwd = direction.try_normalize(1e-12).unwrap_or(-Vector3::z());
    let hint = if fwd.z.abs() > 0.9 { Vector3::x() } else { Vector3::z() };
    let right = fwd.cross(&hint).normalize();
    let up = right.cross(&fwd);
    let r = radius.max(1e-3);
    let depth = (dmax - dmin).max(1e-3);
    let row = |axis: Vector3<f64>, scale: f64, offset: f64| [axis.x * scale, axis.y * scale, axis.z * scale, offset];
    let x = row(right, 1.0 / r, -right.dot(&centre) / r);
    let y = row(up, 1.0 / r, -up.dot(&centre) / r);
    let z = row(fwd, 1.0 / depth, (-fwd.dot(&centre) - dmin) / depth);
    Matrix4::new(
        x[0], x[1], x[2], x[3], //
        y[0], y[1], y[2], y[3], //
        z[0], z[1], z[2], z[3], //
        0.0, 0.0, 0.0, 1.0,
    )
}

/// The shadow map's light transform: it covers the part of the scene inside the view frustum
/// up to [`SHADOW_RANGE`] (so texels stay small in a large scene), and every item along the
/// light direction (so occluders outside the view still cast). `None` when nothing is there.
fn shadow_transform(
    direction: Vector3<f64>,
    ranges: &[ItemRange],
    poses: &[Isometry3<f64>],
    camera: &Isometry3<f64>,
    k: &CameraIntrinsics,
) -> Option<Matrix4<f64>> {
    let (lo, hi) = scene_aabb(ranges, poses)?;
    // Frustum slice corners in the world.
    let (tx, ty) = (k.width as f64 / 2.0 / k.fx(), k.height as f64 / 2.0 / k.fy());
    let mut flo = Vector3::repeat(f64::INFINITY);
    let mut fhi = Vector3::repeat(f64::NEG_INFINITY);
    for z in [k.near, k.far.min(SHADOW_RANGE)] {
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            let p = camera * nalgebra::Point3::new(sx * tx * z, sy * ty * z, z);
            flo = flo.inf(&p.coords);
            fhi = fhi.sup(&p.coords);
        }
    }
    let (rlo, rhi) = (lo.sup(&flo), hi.inf(&fhi));
    if rlo.iter().zip(rhi.iter()).any(|(a, b)| a > b) {
        return None;
    }
    let centre = (rlo + rhi) / 2.0;
    let radius = ((rhi - rlo) / 2.0).norm();
    let fwd = direction.try_normalize(1e-12).unwrap_or(-Vector3::z());
    let (mut dmin, mut dmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..8 {
        let c = Vector3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let d = fwd.dot(&(c - centre));
        dmin = dmin.min(d);
        dmax = dmax.max(d);
    }
    Some(light_matrix(fwd, centre, radius, dmin, dmax))
}

impl GpuCamera {
    /// Colour of background pixels (sRGB bytes): a neutral light-blue sky, the ray-cast
    /// camera's [`BACKGROUND_SRGB`](crate::sensors::shading::BACKGROUND_SRGB) too.
    ///
    /// ```
    /// use hearth_sim::sensors::{CameraIntrinsics, Frame, GpuCamera, Modality, ModalitySet, RenderOptions, VisualScene};
    /// let [r, g, b] = GpuCamera::SKY_RGB;
    /// assert!(r < g && g < b); // a light blue
    /// if hearth_sim::sensors::gpu_adapter().is_err() {
    ///     return; // the rest needs a graphics adapter
    /// }
    /// let k = CameraIntrinsics::new(8, 6, 60.0).unwrap();
    /// let mut cam = GpuCamera::new(&VisualScene::default(), k, RenderOptions::default()).unwrap();
    /// let mut frame = Frame::default();
    /// let rgb = ModalitySet::EMPTY.with(Modality::Rgb);
    /// cam.render(&[], &nalgebra::Isometry3::identity(), rgb, &mut frame).unwrap(); // an empty scene
    /// assert!(frame.rgb.chunks(3).all(|c| c.iter().zip(GpuCamera::SKY_RGB).all(|(&a, b)| a.abs_diff(b) <= 2)));
    /// ```
    pub const SKY_RGB: [u8; 3] = crate::sensors::shading::BACKGROUND_SRGB;

    /// Uploads the scene (tessellated once) and prepares rendering at `intrinsics` with
    /// `options`.
    ///
    /// # Errors
    /// [`SensorError::NoAdapter`] when no adapter exists; [`SensorError::InvalidResolution`] or
    /// [`SensorError::InvalidParameter`] for bad intrinsics (or an image larger than the
    /// device allows), or an `msaa` other than 1 (off) or 4 (checked before any adapter is
    /// requested); [`SensorError::Gpu`] when the device refuses the scene. Never panics.
    ///
    /// ```
    /// use hearth_sim::sensors::{CameraIntrinsics, GpuCamera, RenderOptions, SensorError, VisualScene};
    /// let k = CameraIntrinsics::new(32, 32, 60.0).unwrap();
    /// for msaa in [0, 3] {
    ///     // Refused without an adapter, too.
    ///     let bad = RenderOptions { msaa, ..RenderOptions::default() };
    ///     let err = GpuCamera::new(&VisualScene::default(), k, bad).unwrap_err();
    ///     assert!(matches!(err, SensorError::InvalidParameter { name: "msaa", .. }));
    /// }
    /// if hearth_sim::sensors::gpu_adapter().is_err() {
    ///     return;
    /// }
    /// let cam = GpuCamera::new(&VisualScene::default(), k, RenderOptions::default()).unwrap();
    /// assert_eq!(cam.intrinsics().width, 32);
    /// ```
    pub fn new(scene: &VisualScene, intrinsics: CameraIntrinsics, options: RenderOptions) -> SensorResult<Self> {
        intrinsics.validate()?;
        if !matches!(options.msaa, 1 | 4) {
            return Err(SensorError::InvalidParameter {
                name: "msaa",
                value: options.msaa as f64,
                reason: "the wgpu backend supports 1 (off) or 4 samples",
            });
        }
        let gpu = Gpu::open()?;
        let max_side = gpu.limits.max_texture_dimension_2d;
        if intrinsics.width > max_side || intrinsics.height > max_side {
            return Err(SensorError::InvalidResolution {
                width: intrinsics.width,
                height: intrinsics.height,
                max: max_side,
            });
        }
        let device = &gpu.device;

        let mesh = tessellate::tessellate(scene);
        // Reorder the index buffer: closed shapes first (drawn with back-face culling).
        let mut order: Vec<usize> = (0..scene.items.len()).filter(|&i| mesh.ranges[i].closed).collect();
        order.extend((0..scene.items.len()).filter(|&i| !mesh.ranges[i].closed));
        let mut indices = Vec::with_capacity(mesh.indices.len());
        let mut ranges = mesh.ranges.clone();
        for &i in &order {
            let r = mesh.ranges[i];
            ranges[i].first_index = indices.len() as u32;
            indices.extend_from_slice(&mesh.indices[r.first_index as usize..(r.first_index + r.index_count) as usize]);
        }
        let bytes_or_pad = |b: &[u8]| -> Vec<u8> { if b.is_empty() { vec![0u8; 16] } else { b.to_vec() } };
        let vertex_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hearth camera vertices"),
            contents: &bytes_or_pad(bytemuck::cast_slice(&mesh.vertices)),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hearth camera indices"),
            contents: &bytes_or_pad(bytemuck::cast_slice(&indices)),
            usage: wgpu::BufferUsages::INDEX,
        });
        let n_items = scene.items.len().max(1);
        let xf = vec![[0.0f32; 4]; n_items * XF_FLOATS / 4];
        let xf_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hearth camera transforms"),
            size: (xf.len() * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut materials: Vec<MaterialGpu> = scene
            .items
            .iter()
            .map(|it| MaterialGpu::new(&it.material, it.semantic, it.instance))
            .collect();
        if materials.is_empty() {
            materials.push(MaterialGpu::default());
        }
        let material_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hearth camera materials"),
            contents: bytemuck::cast_slice(&materials),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        });
        materials.truncate(scene.items.len());
        let camera_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hearth camera uniforms"),
            size: std::mem::size_of::<CameraGpu>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });

        let lights: Vec<SceneLight> = scene.lights.iter().take(MAX_LIGHTS).copied().collect();
        let shadow_light = lights
            .iter()
            .position(|l| matches!(l, SceneLight::Directional { .. }))
            .filter(|_| options.shadows);
        let layout = pipeline::scene_bind_group_layout(device, shadow_light.is_some());
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: camera_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: xf_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: material_buf.as_entire_binding(),
            },
        ];
        let mut shadow = None;
        let sampler;
        if let Some(light) = shadow_light {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("hearth camera shadow map"),
                size: wgpu::Extent3d {
                    width: SHADOW_MAP_SIZE,
                    height: SHADOW_MAP_SIZE,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: pipeline::SHADOW_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            });
            let view = texture.create_view(&Default::default());
            sampler = device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("hearth camera shadow sampler"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            });
            let lxf_buf = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("hearth camera light transforms"),
                size: (n_items * 48) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let shadow_layout = pipeline::shadow_bind_group_layout(device);
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hearth camera shadow"),
                layout: &shadow_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: lxf_buf.as_entire_binding(),
                }],
            });
            let pipeline = pipeline::shadow_pipeline(device, &shadow_layout);
            shadow = Some(Shadow {
                view,
                pipeline,
                bind_group,
                lxf_buf,
                last: Vec::new(),
                light,
            });
            let s = shadow.as_ref().map(|s| &s.view);
            if let Some(view) = s {
                entries.push(wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(view),
                });
            }
            entries.push(wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::Sampler(&sampler),
            });
        }
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hearth camera scene"),
            layout: &layout,
            entries: &entries,
        });
        drop(entries);
        gpu.check()?;
        Ok(Self {
            gpu,
            intrinsics,
            options,
            ranges,
            order,
            vertex_buf,
            index_buf,
            xf_buf,
            xf,
            materials,
            material_buf,
            camera_buf,
            lights,
            layout,
            bind_group,
            pipelines: HashMap::new(),
            targets: HashMap::new(),
            depth_view: None,
            msaa_depth_view: None,
            shadow,
            runs: Vec::new(),
            visible: Vec::new(),
            prev_poses: Vec::new(),
            prev_camera: None,
            map_results: Vec::new(),
        })
    }

    /// Name of the adapter rendering (e.g. `llvmpipe (LLVM 19.1.7, 256 bits)`).
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, GpuCamera, Modality, ModalitySet, RenderOptions, VisualScene};
    /// if hearth_sim::sensors::gpu_adapter().is_err() {
    ///     return; // no graphics adapter here
    /// }
    /// let k = CameraIntrinsics::new(8, 6, 60.0).unwrap();
    /// let mut cam = GpuCamera::new(&VisualScene::default(), k, RenderOptions::default()).unwrap();
    /// assert_eq!(cam.adapter_name(), hearth_sim::sensors::gpu_adapter().unwrap());
    /// ```
    pub fn adapter_name(&self) -> &str {
        &self.gpu.name
    }

    /// The intrinsics this camera renders with.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, GpuCamera, Modality, ModalitySet, RenderOptions, VisualScene};
    /// if hearth_sim::sensors::gpu_adapter().is_err() {
    ///     return; // no graphics adapter here
    /// }
    /// let k = CameraIntrinsics::new(8, 6, 60.0).unwrap();
    /// let mut cam = GpuCamera::new(&VisualScene::default(), k, RenderOptions::default()).unwrap();
    /// assert_eq!(cam.intrinsics(), &k);
    /// ```
    pub fn intrinsics(&self) -> &CameraIntrinsics {
        &self.intrinsics
    }

    /// Changes one item's material (for material randomisation); ids stay.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when `item` is not an index into the scene's items.
    ///
    /// ```
    /// use hearth_sim::sensors::{CameraIntrinsics, GpuCamera, PbrMaterial, RenderOptions, VisualScene};
    /// if hearth_sim::sensors::gpu_adapter().is_err() {
    ///     return;
    /// }
    /// let k = CameraIntrinsics::new(16, 16, 60.0).unwrap();
    /// let mut cam = GpuCamera::new(&VisualScene::default(), k, RenderOptions::default()).unwrap();
    /// assert!(cam.set_material(0, PbrMaterial::from_urdf(None, None)).is_err());
    /// ```
    pub fn set_material(&mut self, item: usize, material: PbrMaterial) -> SensorResult<()> {
        let Some(slot) = self.materials.get_mut(item) else {
            return Err(SensorError::InvalidParameter {
                name: "item",
                value: item as f64,
                reason: "must index the scene's items",
            });
        };
        *slot = MaterialGpu::new(&material, slot.semantic, slot.instance);
        let offset = (item * std::mem::size_of::<MaterialGpu>()) as u64;
        self.gpu
            .queue
            .write_buffer(&self.material_buf, offset, bytemuck::bytes_of(&*slot));
        self.gpu.check()
    }

    /// Forgets the previous frame: the next frame's flows are 0.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, GpuCamera, Modality, ModalitySet, RenderOptions, VisualScene};
    /// if hearth_sim::sensors::gpu_adapter().is_err() {
    ///     return; // no graphics adapter here
    /// }
    /// let k = CameraIntrinsics::new(8, 6, 60.0).unwrap();
    /// let mut cam = GpuCamera::new(&VisualScene::default(), k, RenderOptions::default()).unwrap();
    /// use nalgebra::Isometry3;
    /// let flow = ModalitySet::EMPTY.with(Modality::SceneFlow);
    /// let mut frame = Frame::default();
    /// cam.render(&[], &Isometry3::identity(), flow, &mut frame).unwrap();
    /// cam.reset_flow();
    /// cam.render(&[], &Isometry3::translation(0.5, 0.0, 0.0), flow, &mut frame).unwrap();
    /// assert!(frame.scene_flow.iter().all(|f| *f == [0.0; 3]));
    /// ```
    pub fn reset_flow(&mut self) {
        self.prev_camera = None;
    }

    /// Renders the requested modalities into `frame` (which is [prepared](Frame::prepare) to
    /// the camera's size). `item_poses` is the world pose of every item, in the order of the
    /// scene's items ([`VisualScene::world_poses`]); `camera` is the world pose of the optical
    /// frame. The poses are remembered for the next frame's flows.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when `item_poses` does not have one pose per item or
    /// the camera pose is not finite; [`SensorError::Gpu`] when the device fails.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, GpuCamera, Modality, ModalitySet, RenderOptions, VisualScene};
    /// if hearth_sim::sensors::gpu_adapter().is_err() {
    ///     return; // no graphics adapter here
    /// }
    /// let k = CameraIntrinsics::new(8, 6, 60.0).unwrap();
    /// let mut cam = GpuCamera::new(&VisualScene::default(), k, RenderOptions::default()).unwrap();
    /// use nalgebra::Isometry3;
    /// let mut frame = Frame::default();
    /// let depth = ModalitySet::EMPTY.with(Modality::Depth);
    /// cam.render(&[], &Isometry3::identity(), depth, &mut frame).unwrap();
    /// assert_eq!(frame.depth.len(), 8 * 6);
    /// assert!(frame.depth.iter().all(|&d| d == 0.0)); // nothing to see
    /// let one_pose_too_many = [Isometry3::identity()];
    /// assert!(cam.render(&one_pose_too_many, &Isometry3::identity(), depth, &mut frame).is_err());
    /// ```
    pub fn render(
        &mut self,
        item_poses: &[Isometry3<f64>],
        camera: &Isometry3<f64>,
        modalities: ModalitySet,
        frame: &mut Frame,
    ) -> SensorResult<()> {
        crate::sensors::camera::check_render_inputs(item_poses, self.ranges.len(), camera)?;
        let k = self.intrinsics;
        frame.prepare(k.width, k.height, modalities);

        let has = |m: Modality| modalities.contains(m);
        let mut mask = 0u8;
        for (m, t) in [
            (Modality::Rgb, Target::Rgb),
            (Modality::Depth, Target::Depth),
            (Modality::Pc, Target::Depth),
            (Modality::Normal, Target::Normal),
            (Modality::Seg, Target::Ids),
            (Modality::InsSeg, Target::Ids),
            (Modality::SceneFlow, Target::SceneFlow),
            (Modality::OpticalFlow, Target::OpticalFlow),
        ] {
            if has(m) {
                mask |= t.bit();
            }
        }
        if mask != 0 {
            self.draw(item_poses, camera, mask)?;
            self.read_back(mask, frame)?;
        }
        self.prev_poses.clear();
        self.prev_poses.extend_from_slice(item_poses);
        self.prev_camera = Some(*camera);
        Ok(())
    }

    /// Uploads transforms and uniforms, records and submits every pass and the copies.
    fn draw(&mut self, item_poses: &[Isometry3<f64>], camera: &Isometry3<f64>, mask: u8) -> SensorResult<()> {
        let k = self.intrinsics;
        let cam_inv = camera.inverse();
        let prev_inv = self.prev_camera.map(|c| c.inverse());
        let (fx, fy) = (k.fx(), k.fy());
        let (w, h) = (k.width as f64, k.height as f64);
        let (tx, ty) = (w / 2.0 / fx, h / 2.0 / fy);
        let (sx, sy) = ((1.0 + tx * tx).sqrt(), (1.0 + ty * ty).sqrt());
        let mut visible = std::mem::take(&mut self.visible);
        visible.clear();
        visible.resize(self.ranges.len(), false);
        for (i, pose) in item_poses.iter().enumerate() {
            let mv = (cam_inv * pose).to_homogeneous();
            let rows = rows3(&mv);
            let prev_rows = match (prev_inv, self.prev_poses.get(i)) {
                (Some(pi), Some(pp)) => rows3(&(pi * pp).to_homogeneous()),
                _ => rows,
            };
            let b = i * XF_FLOATS / 4;
            self.xf[b..b + 3].copy_from_slice(&rows);
            self.xf[b + 3..b + 6].copy_from_slice(&prev_rows);
            // Frustum test of the bounding sphere.
            let r = self.ranges[i];
            let c = mv.transform_point(&nalgebra::Point3::from(Vector3::from(r.center).cast::<f64>()));
            let rad = r.radius as f64 * 1.0001 + 1e-6;
            visible[i] = c.z + rad >= k.near
                && c.z - rad <= k.far
                && (c.x - tx * c.z) / sx <= rad
                && (-c.x - tx * c.z) / sx <= rad
                && (c.y - ty * c.z) / sy <= rad
                && (-c.y - ty * c.z) / sy <= rad
                && r.index_count > 0;
        }
        self.runs.clear();
        for &i in &self.order {
            if !visible[i] {
                continue;
            }
            let r = self.ranges[i];
            let (start, end) = (r.first_index, r.first_index + r.index_count);
            match self.runs.last_mut() {
                Some(last) if last.1 == start && last.2 == r.closed => last.1 = end,
                _ => self.runs.push((start, end, r.closed)),
            }
        }
        self.visible = visible;

        // Uniforms.
        let (near, far) = (k.near, k.far);
        let up = cam_inv.rotation * Vector3::z();
        let mut u = CameraGpu {
            proj: [
                (2.0 * fx / w) as f32,
                (2.0 * fy / h) as f32,
                (-near / (far - near)) as f32,
                (near * far / (far - near)) as f32,
            ],
            pix: [fx as f32, fy as f32, (w / 2.0) as f32, (h / 2.0) as f32],
            up: [up.x as f32, up.y as f32, up.z as f32, EXPOSURE],
            sky: [SKY_RADIANCE[0], SKY_RADIANCE[1], SKY_RADIANCE[2], 0.0],
            ground: [GROUND_RADIANCE[0], GROUND_RADIANCE[1], GROUND_RADIANCE[2], 0.0],
            counts: [self.lights.len() as u32, 0, SHADOW_MAP_SIZE, 0],
            ..Default::default()
        };
        for (slot, light) in u.lights.iter_mut().zip(&self.lights) {
            *slot = match *light {
                SceneLight::Point {
                    position,
                    color,
                    intensity,
                } => {
                    let p = cam_inv * nalgebra::Point3::from(Vector3::from(position).cast::<f64>());
                    LightGpu {
                        pos: [p.x as f32, p.y as f32, p.z as f32, 1.0],
                        color: [color[0] * intensity, color[1] * intensity, color[2] * intensity, 0.0],
                    }
                }
                SceneLight::Directional {
                    direction,
                    color,
                    intensity,
                } => {
                    let d = Vector3::from(direction).cast::<f64>();
                    let to_light = -(cam_inv.rotation * d.try_normalize(1e-12).unwrap_or(-Vector3::z()));
                    LightGpu {
                        pos: [to_light.x as f32, to_light.y as f32, to_light.z as f32, 0.0],
                        color: [color[0] * intensity, color[1] * intensity, color[2] * intensity, 0.0],
                    }
                }
            };
        }

        let device = &self.gpu.device;
        let queue = &self.gpu.queue;
        queue.write_buffer(&self.xf_buf, 0, bytemuck::cast_slice(&self.xf));

        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("hearth camera frame"),
        });

        // Shadow map (only when colour is asked for).
        if mask & Target::Rgb.bit() != 0
            && let Some(shadow) = self.shadow.as_mut()
            && let Some(SceneLight::Directional { direction, .. }) = self.lights.get(shadow.light).copied()
            && let Some(l) = shadow_transform(Vector3::from(direction).cast(), &self.ranges, item_poses, camera, &k)
        {
            let s = l * camera.to_homogeneous();
            for (col, column) in u.shadow.iter_mut().enumerate() {
                for (row, v) in column.iter_mut().enumerate() {
                    // Column-major for WGSL.
                    *v = s[(row, col)] as f32;
                }
            }
            u.counts[1] = shadow.light as u32 + 1;
            let mut lxf = Vec::with_capacity(item_poses.len() * 3);
            // Items whose bounding sphere misses the light's box cast no shadow in view.
            let (sxy, sz) = (l.fixed_view::<1, 3>(0, 0).norm(), l.fixed_view::<1, 3>(2, 0).norm());
            let mut casts = vec![false; item_poses.len()];
            for (i, pose) in item_poses.iter().enumerate() {
                let m = l * pose.to_homogeneous();
                lxf.extend_from_slice(&rows3(&m));
                let r = self.ranges[i];
                let c = m.transform_point(&nalgebra::Point3::from(Vector3::from(r.center).cast::<f64>()));
                let rad = r.radius as f64 * 1.0001 + 1e-6;
                casts[i] = c.x.abs() - rad * sxy <= 1.0
                    && c.y.abs() - rad * sxy <= 1.0
                    && c.z - rad * sz <= 1.0
                    && c.z + rad * sz >= 0.0;
            }
            if lxf != shadow.last {
                queue.write_buffer(&shadow.lxf_buf, 0, bytemuck::cast_slice(&lxf));
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("hearth camera shadow"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &shadow.view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&shadow.pipeline);
                pass.set_bind_group(0, &shadow.bind_group, &[]);
                pass.set_vertex_buffer(0, self.vertex_buf.slice(..));
                pass.set_index_buffer(self.index_buf.slice(..), wgpu::IndexFormat::Uint32);
                let mut run: Option<(u32, u32)> = None;
                for &i in &self.order {
                    let r = self.ranges[i];
                    if !casts[i] || r.index_count == 0 {
                        continue;
                    }
                    let (start, end) = (r.first_index, r.first_index + r.index_count);
                    run = match run {
                        Some((a, b)) if b == start => Some((a, end)),
                        Some((a, b)) => {
                            pass.draw_indexed(a..b, 0, 0..1);
                            Some((start, end))
                        }
                        None => Some((start, end)),
                    };
                }
                if let Some((a, b)) = run {
                    pass.draw_indexed(a..b, 0, 0..1);
                }
                drop(pass);
                shadow.last = lxf;
            }
        }
        queue.write_buffer(&self.camera_buf, 0, bytemuck::bytes_of(&u));

        // Plan the passes: MSAA colour alone, then the rest grouped within the device limits.
        let msaa = self.options.msaa == 4;
        let mut passes: Vec<(u8, u32)> = Vec::new();
        let mut rest = mask;
        if msaa && mask & Target::Rgb.bit() != 0 {
            passes.push((Target::Rgb.bit(), 4));
            rest &= !Target::Rgb.bit();
        }
        let max_attachments = self.gpu.limits.max_color_attachments.max(1);
        let max_bytes = self.gpu.limits.max_color_attachment_bytes_per_sample;
        let mut cur = 0u8;
        for t in Target::in_mask(rest) {
            let next = cur | t.bit();
            if cur != 0 && (next.count_ones() > max_attachments || pipeline::bytes_per_sample(next) > max_bytes) {
                passes.push((cur, 1));
                cur = t.bit();
            } else {
                cur = next;
            }
        }
        if cur != 0 {
            passes.push((cur, 1));
        }

        // A pass with colour is preceded by a depth-only pre-pass (mask 0) into its depth buffer.
        let passes: Vec<(u8, u32)> = passes
            .into_iter()
            .flat_map(|(m, s)| {
                let pre = (m & Target::Rgb.bit() != 0).then_some((0u8, s));
                pre.into_iter().chain(std::iter::once((m, s)))
            })
            .collect();
        for &(pmask, samples) in &passes {
            self.ensure_resources(pmask, samples);
        }
        let device = &self.gpu.device;
        for &(pmask, samples) in &passes {
            let mut attachments: Vec<Option<wgpu::RenderPassColorAttachment<'_>>> = Vec::new();
            for t in Target::in_mask(pmask) {
                let Some(tex) = self.targets.get(&t) else { continue };
                let ops = wgpu::Operations {
                    load: wgpu::LoadOp::Clear(t.clear(sky_linear())),
                    store: wgpu::StoreOp::Store,
                };
                attachments.push(Some(match (&tex.msaa_view, samples > 1) {
                    (Some(mv), true) => wgpu::RenderPassColorAttachment {
                        view: mv,
                        depth_slice: None,
                        resolve_target: Some(&tex.view),
                        ops: wgpu::Operations {
                            load: ops.load,
                            store: wgpu::StoreOp::Discard,
                        },
                    },
                    _ => wgpu::RenderPassColorAttachment {
                        view: &tex.view,
                        depth_slice: None,
                        resolve_target: None,
                        ops,
                    },
                }));
            }
            let depth_view = if samples > 1 {
                self.msaa_depth_view.as_ref()
            } else {
                self.depth_view.as_ref()
            };
            let Some(depth_view) = depth_view else {
                return Err(SensorError::Gpu("depth buffer missing".into()));
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("hearth camera geometry"),
                color_attachments: &attachments,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth_view,
                    depth_ops: Some(if pmask == 0 {
                        wgpu::Operations {
                            load: wgpu::LoadOp::Clear(0.0),
                            store: wgpu::StoreOp::Store,
                        }
                    } else if pmask & Target::Rgb.bit() != 0 {
                        wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Discard,
                        }
                    } else {
                        wgpu::Operations {
                            load: wgpu::LoadOp::Clear(0.0),
                            store: wgpu::StoreOp::Discard,
                        }
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if !self.runs.is_empty() {
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_vertex_buffer(0, self.vertex_buf.slice(..));
                pass.set_index_buffer(self.index_buf.slice(..), wgpu::IndexFormat::Uint32);
                for closed in [true, false] {
                    let key = PipelineKey {
                        mask: pmask,
                        samples,
                        cull: closed,
                    };
                    let mut bound = false;
                    for &(start, end, c) in &self.runs {
                        if c != closed {
                            continue;
                        }
                        if !bound {
                            let Some(p) = self.pipelines.get(&key) else { continue };
                            pass.set_pipeline(p);
                            bound = true;
                        }
                        pass.draw_indexed(start..end, 0, 0..1);
                    }
                }
            }
        }
        // Copies to the staging buffers.
        for t in Target::in_mask(mask) {
            let Some(tex) = self.targets.get(&t) else { continue };
            encoder.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture: &tex.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: &tex.staging,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(tex.padded_row),
                        rows_per_image: Some(k.height),
                    },
                },
                wgpu::Extent3d {
                    width: k.width,
                    height: k.height,
                    depth_or_array_layers: 1,
                },
            );
        }
        let _ = device;
        self.gpu.queue.submit(Some(encoder.finish()));
        self.gpu.check()
    }

    /// Creates the targets, depth buffers and pipelines a pass needs.
    fn ensure_resources(&mut self, mask: u8, samples: u32) {
        let k = self.intrinsics;
        let device = &self.gpu.device;
        let size = wgpu::Extent3d {
            width: k.width,
            height: k.height,
            depth_or_array_layers: 1,
        };
        let texture = |label: &str, format: wgpu::TextureFormat, samples: u32, usage: wgpu::TextureUsages| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        for t in Target::in_mask(mask) {
            let tex = self.targets.entry(t).or_insert_with(|| {
                let texture = texture(
                    "hearth camera target",
                    t.format(),
                    1,
                    wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                );
                let padded_row = (k.width * t.texel_bytes()).div_ceil(ROW_ALIGN) * ROW_ALIGN;
                let staging = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("hearth camera read-back"),
                    size: padded_row as u64 * k.height as u64,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                TargetTex {
                    view: texture.create_view(&Default::default()),
                    texture,
                    msaa_view: None,
                    staging,
                    padded_row,
                }
            });
            if samples > 1 && tex.msaa_view.is_none() {
                let ms = texture(
                    "hearth camera msaa colour",
                    t.format(),
                    samples,
                    wgpu::TextureUsages::RENDER_ATTACHMENT,
                );
                tex.msaa_view = Some(ms.create_view(&Default::default()));
            }
        }
        let depth_slot = if samples > 1 {
            &mut self.msaa_depth_view
        } else {
            &mut self.depth_view
        };
        if depth_slot.is_none() {
            let d = texture(
                "hearth camera depth",
                pipeline::DEPTH_FORMAT,
                samples,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            );
            *depth_slot = Some(d.create_view(&Default::default()));
        }
        for cull in [true, false] {
            let key = PipelineKey { mask, samples, cull };
            let used = self.runs.iter().any(|r| r.2 == cull);
            if used && !self.pipelines.contains_key(&key) {
                let p = pipeline::scene_pipeline(device, &self.layout, key, self.options.pbr, self.shadow.is_some());
                self.pipelines.insert(key, p);
            }
        }
    }

    /// Maps the staging buffers of `mask`, waits, and un-pads them into `frame`.
    fn read_back(&mut self, mask: u8, frame: &mut Frame) -> SensorResult<()> {
        let targets: Vec<Target> = Target::in_mask(mask).collect();
        while self.map_results.len() < targets.len() {
            self.map_results.push(Arc::new(Mutex::new(None)));
        }
        for (t, slot) in targets.iter().zip(&self.map_results) {
            let Some(tex) = self.targets.get(t) else {
                return Err(SensorError::Gpu(format!("target {t:?} missing")));
            };
            *slot.lock().unwrap_or_else(|p| p.into_inner()) = None;
            let sink = Arc::clone(slot);
            tex.staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                *sink.lock().unwrap_or_else(|p| p.into_inner()) = Some(r);
            });
        }
        let polled = self.gpu.device.poll(wgpu::PollType::wait_indefinitely());
        let checked = self.gpu.check();
        let mut result = polled
            .map(|_| ())
            .map_err(|e| SensorError::Gpu(format!("waiting for the frame: {e}")))
            .and(checked);
        let k = self.intrinsics;
        let (w, h) = (k.width as usize, k.height as usize);
        for (t, slot) in targets.iter().zip(&self.map_results) {
            let Some(tex) = self.targets.get(t) else { continue };
            let mapped = slot.lock().unwrap_or_else(|p| p.into_inner()).take();
            match mapped {
                Some(Ok(())) => {}
                Some(Err(e)) => {
                    result = result.and(Err(SensorError::Gpu(format!("read-back failed: {e}"))));
                    continue;
                }
                None => {
                    result = result.and(Err(SensorError::Gpu("read-back did not complete".into())));
                    continue;
                }
            }
            if result.is_ok() {
                match tex.staging.slice(..).get_mapped_range() {
                    Ok(view) => unpad(*t, &view, tex.padded_row as usize, w, h, &k, frame),
                    Err(e) => result = Err(SensorError::Gpu(format!("read-back failed: {e}"))),
                }
            }
            tex.staging.unmap();
        }
        result
    }
}

/// Linear RGB of the sky clear colour (what the sRGB target encodes to [`GpuCamera::SKY_RGB`]).
fn sky_linear() -> [f64; 3] {
    GpuCamera::SKY_RGB.map(|c| srgb_to_linear(c as f64 / 255.0))
}

/// Axis-aligned box around every item's bounding sphere at `poses` (`None`: no geometry).
fn scene_aabb(ranges: &[ItemRange], poses: &[Isometry3<f64>]) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for (r, p) in ranges.iter().zip(poses) {
        if r.index_count == 0 {
            continue;
        }
        let c = p * nalgebra::Point3::from(Vector3::from(r.center).cast::<f64>());
        let rad = Vector3::repeat(r.radius as f64);
        if c.coords.iter().all(|x| x.is_finite()) {
            lo = lo.inf(&(c.coords - rad));
            hi = hi.sup(&(c.coords + rad));
        }
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// Copies one mapped target (rows `padded_row` bytes apart) into `frame`.
fn unpad(t: Target, data: &[u8], padded_row: usize, w: usize, h: usize, k: &CameraIntrinsics, frame: &mut Frame) {
    let has = |m: Modality| frame.modalities.contains(m);
    let row = |v: usize| &data[v * padded_row..v * padded_row + w * t.texel_bytes() as usize];
    let f32_at = |b: &[u8], i: usize| f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    let u32_at = |b: &[u8], i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    match t {
        Target::Rgb => {
            for v in 0..h {
                let src = row(v);
                let dst = &mut frame.rgb[v * w * 3..(v + 1) * w * 3];
                for (d, s) in dst.chunks_exact_mut(3).zip(src.chunks_exact(4)) {
                    d.copy_from_slice(&s[..3]);
                }
            }
        }
        Target::Depth => {
            let (near, far) = (k.near as f32, k.far as f32);
            let (cx, cy) = k.principal_point();
            let (fx, fy) = (k.fx(), k.fy());
            let (want_depth, want_pc) = (has(Modality::Depth), has(Modality::Pc));
            for v in 0..h {
                let src = row(v);
                let ry = ((v as f64 + 0.5 - cy) / fy) as f32;
                for u in 0..w {
                    let mut z = f32_at(src, 4 * u);
                    if !(z >= near && z <= far) {
                        z = 0.0;
                    }
                    let i = v * w + u;
                    if want_depth {
                        frame.depth[i] = z;
                    }
                    if want_pc {
                        let rx = ((u as f64 + 0.5 - cx) / fx) as f32;
                        frame.pc[i] = [rx * z, ry * z, z];
                    }
                }
            }
        }
        Target::Normal => {
            for v in 0..h {
                let src = row(v);
                for u in 0..w {
                    let o = 8 * u;
                    let c = |j: usize| f16_to_f32(u16::from_le_bytes([src[o + 2 * j], src[o + 2 * j + 1]]));
                    frame.normal[v * w + u] = [c(0), c(1), c(2)];
                }
            }
        }
        Target::Ids => {
            let (want_seg, want_ins) = (has(Modality::Seg), has(Modality::InsSeg));
            for v in 0..h {
                let src = row(v);
                for u in 0..w {
                    let i = v * w + u;
                    if want_seg {
                        frame.seg[i] = u32_at(src, 8 * u);
                    }
                    if want_ins {
                        frame.ins_seg[i] = u32_at(src, 8 * u + 4);
                    }
                }
            }
        }
        Target::SceneFlow => {
            for v in 0..h {
                let src = row(v);
                for u in 0..w {
                    let o = 16 * u;
                    frame.scene_flow[v * w + u] = [f32_at(src, o), f32_at(src, o + 4), f32_at(src, o + 8)];
                }
            }
        }
        Target::OpticalFlow => {
            for v in 0..h {
                let src = row(v);
                for u in 0..w {
                    let o = 8 * u;
                    frame.optical_flow[v * w + u] = [f32_at(src, o), f32_at(src, o + 4)];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_decode() {
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xbc00), -1.0);
        assert_eq!(f16_to_f32(0x0000), 0.0);
        assert_eq!(f16_to_f32(0x3800), 0.5);
        assert!((f16_to_f32(0x3bff) - 0.99951).abs() < 1e-4);
        assert_eq!(f16_to_f32(0x0001), 2.0f32.powi(-24));
    }

    /// Every one of the 65,536 half floats decodes to the value its fields define.
    #[test]
    fn half_floats_decode_exactly() {
        for h in 0..=u16::MAX {
            let negative = h & 0x8000 != 0;
            let (exp, man) = (i32::from((h >> 10) & 0x1f), f64::from(h & 0x3ff));
            let magnitude = match exp {
                0 => man * 2f64.powi(-24),
                31 if man == 0.0 => f64::INFINITY,
                31 => f64::NAN,
                _ => (1.0 + man / 1024.0) * 2f64.powi(exp - 15),
            };
            let got = f16_to_f32(h);
            if magnitude.is_nan() {
                assert!(got.is_nan(), "{h:#06x}");
            } else {
                assert_eq!(
                    got.to_bits(),
                    ((if negative { -magnitude } else { magnitude }) as f32).to_bits(),
                    "{h:#06x}"
                );
            }
        }
    }

    #[test]
    fn light_matrix_maps_the_sphere_into_the_unit_box() {
        let c = Vector3::new(1.0, 2.0, 3.0);
        let l = light_matrix(Vector3::new(0.3, 0.4, -1.0), c, 2.0, -2.0, 2.0);
        let p = l * c.push(1.0);
        assert!(p.x.abs() < 1e-12 && p.y.abs() < 1e-12 && (p.z - 0.5).abs() < 1e-12);
        let d = Vector3::new(0.3, 0.4, -1.0).normalize();
        let far = l * (c + d * 2.0).push(1.0);
        assert!((far.z - 1.0).abs() < 1e-12);
    }

    /// Sample counts other than 1 and 4 are refused as a bad setting before any adapter is
    /// requested (so without a GPU, too); 0 used to pass and render single-sampled.
    #[test]
    fn unsupported_msaa_counts_are_invalid_parameters() {
        let k = CameraIntrinsics::new(16, 16, 60.0).unwrap();
        for msaa in [0, 2, 3, 8, 16, u32::MAX] {
            let options = RenderOptions {
                msaa,
                ..RenderOptions::default()
            };
            let err = GpuCamera::new(&VisualScene::default(), k, options).err();
            assert!(
                matches!(err, Some(SensorError::InvalidParameter { name: "msaa", .. })),
                "msaa {msaa}: {err:?}"
            );
        }
    }
}
