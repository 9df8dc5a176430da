//! [`RasterCamera`]: a CPU depth rasteriser for the geometric modalities (depth, point cloud,
//! normals, semantic and instance ids), the fast choice for RL observations without colour.
//!
//! The scene is tessellated once into the same triangles the wgpu backend draws. Each frame
//! every item whose bounding sphere meets the view frustum has its vertices moved into the
//! camera frame; its triangles are clipped against the near plane, back faces of closed shapes
//! are skipped, and the rest are filled into a z-buffer at pixel centres. The depth of a pixel
//! comes from the triangle's plane (1/z is affine in the pixel coordinates), so a flat face
//! reads the same depth as a ray cast through that pixel, up to f32 rounding.
//!
//! Normals are the flat normals of the triangles (a tessellated cylinder or sphere shows its
//! facets). Colour and flows need the wgpu or ray-cast backend.

use nalgebra::Isometry3;

use super::camera::{CameraIntrinsics, Frame, Modality, ModalitySet, check_render_inputs};
use super::error::{SensorError, SensorResult};
use super::gpu::tessellate::{ItemRange, cross, dot, sub, tessellate};
use super::visuals::VisualScene;

/// Item id of a pixel that sees nothing.
const NO_ITEM: u32 = u32::MAX;

/// The modalities [`RasterCamera`] renders.
///
/// ```
/// use hearth_sim::sensors::{Modality, RASTER_MODALITIES};
/// assert!(RASTER_MODALITIES.contains(Modality::Depth));
/// assert!(!RASTER_MODALITIES.contains(Modality::Rgb));
/// ```
pub const RASTER_MODALITIES: ModalitySet = ModalitySet::EMPTY
    .with(Modality::Depth)
    .with(Modality::Pc)
    .with(Modality::Normal)
    .with(Modality::Seg)
    .with(Modality::InsSeg);

/// Per-frame constants of the projection.
#[derive(Clone, Copy, Debug)]
struct Projection {
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
    near: f32,
    width: usize,
    height: usize,
}

impl Projection {
    /// Continuous pixel coordinates of a camera-frame point with z > 0.
    #[inline(always)]
    fn project(&self, p: [f32; 3]) -> [f32; 2] {
        let iz = 1.0 / p[2];
        [self.fx * p[0] * iz + self.cx, self.fy * p[1] * iz + self.cy]
    }
}

fn lerp(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// Largest integer not above `x` (saturating), without a libm call.
#[inline(always)]
fn floor_i(x: f32) -> i32 {
    let i = x as i32;
    i - ((i as f32) > x) as i32
}

/// Smallest integer not below `x` (saturating), without a libm call.
#[inline(always)]
fn ceil_i(x: f32) -> i32 {
    let i = x as i32;
    i + ((i as f32) < x) as i32
}

/// How an edge bounds the pixels of a row.
#[derive(Clone, Copy, Debug, PartialEq)]
enum EdgeKind {
    /// Inside is x ≥ slope·y + offset.
    Left,
    /// Inside is x ≤ slope·y + offset.
    Right,
    /// A horizontal edge: inside is slope·y + offset ≥ 0.
    Flat,
}

/// A screen triangle ready to fill: its edges as bounds on x per row, its 1/z plane and its
/// pixel box.
#[derive(Clone, Copy, Debug)]
struct Setup {
    edges: [(EdgeKind, f32, f32); 3],
    /// 1/z = a·x + b·y + c at pixel centre (x, y).
    plane: [f32; 3],
    /// Pixel box (inclusive).
    u0: i32,
    u1: i32,
    v0: u32,
    v1: u32,
    /// Index of the source triangle.
    tri: u32,
}

impl Setup {
    /// The screen triangle `s` (pixel coordinates) with 1/z `plane`, or `None` when it covers
    /// no pixel centre.
    #[inline]
    fn new(k: &Projection, s: [[f32; 2]; 3], plane: [f32; 3], tri: u32) -> Option<Self> {
        let [p0, p1, p2] = s;
        let area = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
        if area.is_nan() || area.abs() <= 1e-12 {
            return None;
        }
        // Counter-clockwise in pixel coordinates from here on.
        let (p1, p2) = if area > 0.0 { (p1, p2) } else { (p2, p1) };
        let xmin = p0[0].min(p1[0]).min(p2[0]);
        let xmax = p0[0].max(p1[0]).max(p2[0]);
        let ymin = p0[1].min(p1[1]).min(p2[1]);
        let ymax = p0[1].max(p1[1]).max(p2[1]);
        // Pixels whose centres (i + ½) fall in the box.
        let (w, h) = (k.width as f32, k.height as f32);
        if !(xmax >= 0.5 && ymax >= 0.5 && xmin <= w - 0.5 && ymin <= h - 0.5) {
            return None;
        }
        let u0 = ceil_i(xmin - 0.5).max(0);
        let u1 = floor_i(xmax - 0.5).min(k.width as i32 - 1);
        let v0 = ceil_i(ymin - 0.5).max(0);
        let v1 = floor_i(ymax - 0.5).min(k.height as i32 - 1);
        if u0 > u1 || v0 > v1 {
            return None;
        }
        // Edge function e(x, y) = A x + B y + C ≥ 0 inside, solved for x per row.
        let edge = |a: [f32; 2], b: [f32; 2]| {
            let (ea, eb, ec) = (a[1] - b[1], b[0] - a[0], a[0] * b[1] - a[1] * b[0]);
            if ea > 0.0 {
                (EdgeKind::Left, -eb / ea, -ec / ea)
            } else if ea < 0.0 {
                (EdgeKind::Right, -eb / ea, -ec / ea)
            } else {
                (EdgeKind::Flat, eb, ec)
            }
        };
        Some(Self {
            edges: [edge(p0, p1), edge(p1, p2), edge(p2, p0)],
            plane,
            u0,
            u1,
            v0: v0 as u32,
            v1: v1 as u32,
            tri,
        })
    }

    /// Fills the triangle's pixels in `band` where it is nearer than what is there (and
    /// records the triangle per pixel when `IDS`).
    #[inline]
    fn fill<const IDS: bool>(&self, band: &mut Band<'_>) {
        let v0 = (self.v0 as usize).max(band.first_row);
        let v1 = (self.v1 as usize).min(band.first_row + band.rows - 1);
        let [pa, pb, pc] = self.plane;
        for v in v0..=v1 {
            let y = v as f32 + 0.5;
            // The span of the row inside all three edges.
            let (mut lo, mut hi) = (f32::NEG_INFINITY, f32::INFINITY);
            let mut empty = false;
            for (kind, slope, offset) in self.edges {
                let x = slope * y + offset;
                match kind {
                    EdgeKind::Left => lo = lo.max(x),
                    EdgeKind::Right => hi = hi.min(x),
                    EdgeKind::Flat => empty |= x < 0.0,
                }
            }
            let a = ceil_i(lo - 0.5).max(self.u0);
            let b = floor_i(hi - 0.5).min(self.u1);
            // `lo` and `hi` are never NaN (`f32::max`/`min` drop a NaN operand).
            if empty || lo > hi || a > b {
                continue;
            }
            let (a, b) = (a as usize, b as usize);
            let row = (v - band.first_row) * band.width;
            let base = pb * y + pc;
            let inv_z = &mut band.inv_z[row + a..=row + b];
            let x0 = a as f32 + 0.5;
            if IDS {
                let tris = &mut band.tri[row + a..=row + b];
                for (j, (z, t)) in inv_z.iter_mut().zip(tris.iter_mut()).enumerate() {
                    let iz = pa * (x0 + (j as i32) as f32) + base;
                    if iz > *z {
                        *z = iz;
                        *t = self.tri;
                    }
                }
            } else {
                for (j, z) in inv_z.iter_mut().enumerate() {
                    let iz = pa * (x0 + (j as i32) as f32) + base;
                    // A plain compare (no NaN rules) lets this loop run on SIMD lanes.
                    *z = if iz > *z { iz } else { *z };
                }
            }
        }
    }
}

/// Rows `first_row..first_row + rows` of the z-buffer.
struct Band<'a> {
    inv_z: &'a mut [f32],
    tri: &'a mut [u32],
    first_row: usize,
    rows: usize,
    width: usize,
}

impl Band<'_> {
    /// Fills every setup that reaches the band (recording triangles when `ids`).
    fn fill_all(&mut self, setups: &[Setup], ids: bool) {
        let (r0, r1) = (self.first_row as u32, (self.first_row + self.rows) as u32);
        for s in setups {
            if s.v1 >= r0 && s.v0 < r1 {
                if ids {
                    s.fill::<true>(self);
                } else {
                    s.fill::<false>(self);
                }
            }
        }
    }
}

/// Images of at least this many pixels are filled in two bands on two threads.
const PARALLEL_MIN_PIXELS: usize = 64 * 64;

/// The CPU depth rasteriser backend (see the [module docs](self)).
///
/// ```
/// use hearth_sim::sensors::{CameraIntrinsics, Frame, Modality, ModalitySet, Mount, RasterCamera, VisualScene};
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::{Isometry3, Point3};
///
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), false).unwrap();
/// let scene = VisualScene::from_world(&world);
/// let k = CameraIntrinsics::new(64, 64, 60.0).unwrap();
/// let mut camera = RasterCamera::new(&scene, k).unwrap();
/// let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap() else { unreachable!() };
/// let mut frame = Frame::default();
/// let set = ModalitySet::EMPTY.with(Modality::Depth);
/// camera.render(&scene.world_poses(&world), &pose, set, &mut frame).unwrap();
/// let centre = frame.depth[frame.index(32, 32)];
/// assert!((centre - 2.5).abs() < 1e-3, "{centre}");
/// ```
#[derive(Debug)]
pub struct RasterCamera {
    intrinsics: CameraIntrinsics,
    /// Item-frame vertex positions of the tessellated scene.
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    ranges: Vec<ItemRange>,
    /// Per item: its vertex range.
    vertex_ranges: Vec<(u32, u32)>,
    /// Per triangle: the item it belongs to.
    tri_item: Vec<u32>,
    /// Per item: (semantic, instance).
    ids: Vec<(u32, u32)>,
    /// Scratch: camera-frame vertices of the visible items.
    cam_vertices: Vec<[f32; 3]>,
    /// Scratch: per vertex, the frustum sides it lies beyond (see [`outcode`]).
    outcodes: Vec<u8>,
    /// Per pixel: 1/z of the nearest surface (0: nothing).
    inv_z: Vec<f32>,
    /// Per pixel: the triangle seen (index into the index buffer / 3).
    tri: Vec<u32>,
    /// Scratch: the triangles of this frame, set up for filling.
    setups: Vec<Setup>,
    /// Items drawn in the last frame.
    drawn: usize,
}

impl RasterCamera {
    /// A rasteriser over `scene`'s shapes and ids.
    ///
    /// # Errors
    /// [`SensorError::InvalidResolution`] / [`SensorError::InvalidParameter`] for bad intrinsics.
    ///
    /// ```
    /// use hearth_sim::sensors::{CameraIntrinsics, RasterCamera, VisualScene};
    /// let scene = VisualScene::default();
    /// let camera = RasterCamera::new(&scene, CameraIntrinsics::new(32, 24, 60.0).unwrap()).unwrap();
    /// assert_eq!(camera.triangles(), 0);
    /// let mut bad = CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// bad.width = 0;
    /// assert!(RasterCamera::new(&scene, bad).is_err());
    /// ```
    pub fn new(scene: &VisualScene, intrinsics: CameraIntrinsics) -> SensorResult<Self> {
        intrinsics.validate()?;
        let mesh = tessellate(scene);
        let n = scene.items.len();
        let mut vertex_ranges = vec![(0u32, 0u32); n];
        let mut start = 0usize;
        while start < mesh.vertices.len() {
            let item = mesh.vertices[start].item;
            let mut end = start;
            while end < mesh.vertices.len() && mesh.vertices[end].item == item {
                end += 1;
            }
            if let Some(r) = vertex_ranges.get_mut(item as usize) {
                *r = (start as u32, end as u32);
            }
            start = end;
        }
        let mut tri_item = vec![0u32; mesh.indices.len() / 3];
        for (i, r) in mesh.ranges.iter().enumerate() {
            let first = r.first_index as usize / 3;
            for t in &mut tri_item[first..first + r.index_count as usize / 3] {
                *t = i as u32;
            }
        }
        Ok(Self {
            intrinsics,
            positions: mesh.vertices.iter().map(|v| v.pos).collect(),
            cam_vertices: vec![[0.0; 3]; mesh.vertices.len()],
            outcodes: vec![0; mesh.vertices.len()],
            indices: mesh.indices,
            ranges: mesh.ranges,
            vertex_ranges,
            tri_item,
            ids: scene.items.iter().map(|i| (i.semantic, i.instance)).collect(),
            inv_z: Vec::new(),
            tri: Vec::new(),
            setups: Vec::new(),
            drawn: 0,
        })
    }

    /// The intrinsics.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, Modality, ModalitySet, Mount, RasterCamera, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), false).unwrap();
    /// # let scene = VisualScene::from_world(&world);
    /// # let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap() else { unreachable!() };
    /// let mut camera = RasterCamera::new(&scene, CameraIntrinsics::new(32, 24, 60.0).unwrap()).unwrap();
    /// assert_eq!((camera.intrinsics().width, camera.intrinsics().height), (32, 24));
    /// ```
    pub fn intrinsics(&self) -> &CameraIntrinsics {
        &self.intrinsics
    }

    /// Number of triangles of the tessellated scene.
    ///
    /// ```
    /// use hearth_sim::sensors::{CameraIntrinsics, RasterCamera, VisualScene};
    /// use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig { ground_plane: false, ..Default::default() }).unwrap();
    /// world.add_box("crate", [0.5; 3], &nalgebra::Isometry3::identity(), false).unwrap();
    /// let camera = RasterCamera::new(&VisualScene::from_world(&world), CameraIntrinsics::new(8, 8, 60.0).unwrap()).unwrap();
    /// assert_eq!(camera.triangles(), 12);
    /// assert_eq!(camera.items_drawn(), 0, "nothing rendered yet");
    /// ```
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }

    /// How many items passed the frustum test in the last frame.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, Modality, ModalitySet, Mount, RasterCamera, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), false).unwrap();
    /// # let scene = VisualScene::from_world(&world);
    /// # let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap() else { unreachable!() };
    /// let mut camera = RasterCamera::new(&scene, CameraIntrinsics::new(32, 24, 60.0).unwrap()).unwrap();
    /// let mut frame = Frame::default();
    /// let depth = ModalitySet::EMPTY.with(Modality::Depth);
    /// camera.render(&scene.world_poses(&world), &pose, depth, &mut frame).unwrap();
    /// assert_eq!(camera.items_drawn(), 2); // the ground and the crate
    /// ```
    pub fn items_drawn(&self) -> usize {
        self.drawn
    }

    /// Renders `modalities` into `frame` with the items at `item_poses` (one world pose per
    /// scene item) and the optical frame at `camera`.
    ///
    /// # Errors
    /// [`SensorError::Unsupported`] when `modalities` holds colour or flow;
    /// [`SensorError::InvalidParameter`] when `item_poses` has the wrong length or `camera` is
    /// not finite.
    ///
    /// ```
    /// # use hearth_sim::sensors::{CameraIntrinsics, Frame, Modality, ModalitySet, Mount, RasterCamera, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::{Isometry3, Point3};
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("crate", [0.5; 3], &Isometry3::translation(3.0, 0.0, 0.5), false).unwrap();
    /// # let scene = VisualScene::from_world(&world);
    /// # let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 0.5), Point3::new(3.0, 0.0, 0.5)).unwrap() else { unreachable!() };
    /// let mut camera = RasterCamera::new(&scene, CameraIntrinsics::new(32, 24, 60.0).unwrap()).unwrap();
    /// let mut frame = Frame::default();
    /// let poses = scene.world_poses(&world);
    /// let set = ModalitySet::EMPTY.with(Modality::Depth).with(Modality::InsSeg);
    /// camera.render(&poses, &pose, set, &mut frame).unwrap();
    /// assert!((frame.depth[frame.index(16, 12)] - 2.5).abs() < 1e-3);
    /// assert_eq!(frame.ins_seg[frame.index(16, 12)], 2); // the crate
    /// let rgb = ModalitySet::EMPTY.with(Modality::Rgb);
    /// assert!(camera.render(&poses, &pose, rgb, &mut frame).is_err()); // no colour here
    /// ```
    pub fn render(
        &mut self,
        item_poses: &[Isometry3<f64>],
        camera: &Isometry3<f64>,
        modalities: ModalitySet,
        frame: &mut Frame,
    ) -> SensorResult<()> {
        if let Some(m) = modalities.iter().find(|m| !RASTER_MODALITIES.contains(*m)) {
            return Err(SensorError::Unsupported {
                backend: "raster",
                modality: m.name(),
            });
        }
        check_render_inputs(item_poses, self.ids.len(), camera)?;
        let k = self.intrinsics;
        let proj = Projection {
            fx: k.fx() as f32,
            fy: k.fy() as f32,
            cx: k.principal_point().0 as f32,
            cy: k.principal_point().1 as f32,
            near: k.near as f32,
            width: k.width as usize,
            height: k.height as usize,
        };
        self.setups.clear();
        let cam_inv = camera.inverse();
        let (tx, ty) = (k.width as f64 / 2.0 / k.fx(), k.height as f64 / 2.0 / k.fy());
        let (sx, sy) = ((1.0 + tx * tx).sqrt(), (1.0 + ty * ty).sqrt());
        self.drawn = 0;
        let frustum = Frustum {
            tx: tx as f32,
            ty: ty as f32,
            near: k.near as f32,
            far: k.far as f32,
        };
        for (i, pose) in item_poses.iter().enumerate() {
            let r = self.ranges[i];
            if r.index_count == 0 {
                continue;
            }
            let mv = cam_inv * pose;
            // Frustum test of the bounding sphere (as the wgpu backend does).
            let c = mv * nalgebra::Point3::new(r.center[0] as f64, r.center[1] as f64, r.center[2] as f64);
            let rad = r.radius as f64 * 1.0001 + 1e-6;
            let visible = c.z + rad >= k.near
                && c.z - rad <= k.far
                && (c.x - tx * c.z) / sx <= rad
                && (-c.x - tx * c.z) / sx <= rad
                && (c.y - ty * c.z) / sy <= rad
                && (-c.y - ty * c.z) / sy <= rad;
            if !visible {
                continue;
            }
            self.drawn += 1;
            let m = mv.to_homogeneous().cast::<f32>();
            let (v0, v1) = self.vertex_ranges[i];
            let range = v0 as usize..v1 as usize;
            for ((dst, code), p) in self.cam_vertices[range.clone()]
                .iter_mut()
                .zip(&mut self.outcodes[range.clone()])
                .zip(&self.positions[range])
            {
                let q = [
                    m[(0, 0)] * p[0] + m[(0, 1)] * p[1] + m[(0, 2)] * p[2] + m[(0, 3)],
                    m[(1, 0)] * p[0] + m[(1, 1)] * p[1] + m[(1, 2)] * p[2] + m[(1, 3)],
                    m[(2, 0)] * p[0] + m[(2, 1)] * p[1] + m[(2, 2)] * p[2] + m[(2, 3)],
                ];
                *dst = q;
                *code = outcode(q, &frustum);
            }
            let first = r.first_index as usize;
            for t in (first..first + r.index_count as usize).step_by(3) {
                let v = [self.indices[t], self.indices[t + 1], self.indices[t + 2]];
                // Wholly beyond one side of the frustum: no pixel centre sees it.
                if v.iter().fold(u8::MAX, |acc, &i| acc & self.outcodes[i as usize]) != 0 {
                    continue;
                }
                let tri = v.map(|i| self.cam_vertices[i as usize]);
                setup_triangle(&mut self.setups, &proj, tri, r.closed, (t / 3) as u32);
            }
        }
        let ids = [Modality::Normal, Modality::Seg, Modality::InsSeg]
            .iter()
            .any(|m| modalities.contains(*m));
        self.fill(&proj, ids);
        self.resolve(&proj, modalities, frame);
        Ok(())
    }

    /// Clears the z-buffer and fills this frame's triangles into it, in two bands on two
    /// threads for larger images (each pixel sees the triangles in the same order either way).
    fn fill(&mut self, k: &Projection, ids: bool) {
        let pixels = k.width * k.height;
        self.inv_z.clear();
        self.inv_z.resize(pixels, 0.0);
        self.tri.clear();
        self.tri.resize(pixels, NO_ITEM);
        let setups = &self.setups[..];
        if pixels >= PARALLEL_MIN_PIXELS && k.height >= 2 && rayon::current_num_threads() >= 2 {
            let top = k.height / 2;
            let (za, zb) = self.inv_z.split_at_mut(top * k.width);
            let (ta, tb) = self.tri.split_at_mut(top * k.width);
            let mut a = Band {
                inv_z: za,
                tri: ta,
                first_row: 0,
                rows: top,
                width: k.width,
            };
            let mut b = Band {
                inv_z: zb,
                tri: tb,
                first_row: top,
                rows: k.height - top,
                width: k.width,
            };
            rayon::join(|| a.fill_all(setups, ids), || b.fill_all(setups, ids));
        } else {
            Band {
                inv_z: &mut self.inv_z,
                tri: &mut self.tri,
                first_row: 0,
                rows: k.height,
                width: k.width,
            }
            .fill_all(setups, ids);
        }
    }

    /// Turns the z-buffer into the frame's modalities.
    fn resolve(&self, k: &Projection, modalities: ModalitySet, frame: &mut Frame) {
        let kk = self.intrinsics;
        frame.prepare(kk.width, kk.height, modalities);
        let (near, far) = (kk.near as f32, kk.far as f32);
        let want = |m| modalities.contains(m);
        let (depth, pc, normal, seg, ins) = (
            want(Modality::Depth),
            want(Modality::Pc),
            want(Modality::Normal),
            want(Modality::Seg),
            want(Modality::InsSeg),
        );
        // 1/0 is +∞, beyond `far`: pixels that saw nothing read 0 like out-of-range ones.
        let depth_of = |iz: f32| {
            let z = 1.0 / iz;
            if z >= near && z <= far { z } else { 0.0 }
        };
        if depth {
            for (d, &iz) in frame.depth.iter_mut().zip(&self.inv_z) {
                *d = depth_of(iz);
            }
        }
        if pc {
            for v in 0..k.height {
                let ry = (v as f32 + 0.5 - k.cy) / k.fy;
                for u in 0..k.width {
                    let i = v * k.width + u;
                    let z = depth_of(self.inv_z[i]);
                    let rx = (u as f32 + 0.5 - k.cx) / k.fx;
                    frame.pc[i] = [rx * z, ry * z, z];
                }
            }
        }
        if normal || seg || ins {
            for (i, &iz) in self.inv_z.iter().enumerate() {
                let seen = depth_of(iz) > 0.0;
                if normal {
                    frame.normal[i] = if seen { self.normal_of(self.tri[i]) } else { [0.0; 3] };
                }
                let (s, n) = if seen {
                    self.ids[self.tri_item[self.tri[i] as usize] as usize]
                } else {
                    (0, 0)
                };
                if seg {
                    frame.seg[i] = s;
                }
                if ins {
                    frame.ins_seg[i] = n;
                }
            }
        }
    }

    /// Camera-frame unit normal of triangle `tri`, facing the camera.
    fn normal_of(&self, tri: u32) -> [f32; 3] {
        let t = tri as usize * 3;
        let [a, b, c] =
            [self.indices[t], self.indices[t + 1], self.indices[t + 2]].map(|v| self.cam_vertices[v as usize]);
        let n = cross(sub(b, a), sub(c, a));
        let len = dot(n, n).sqrt();
        if len <= 0.0 {
            return [0.0; 3];
        }
        let s = if dot(n, a) > 0.0 { -1.0 / len } else { 1.0 / len };
        [n[0] * s, n[1] * s, n[2] * s]
    }
}

/// The view frustum in the camera frame: |x| ≤ tx·z, |y| ≤ ty·z, near ≤ z ≤ far.
#[derive(Clone, Copy, Debug)]
struct Frustum {
    tx: f32,
    ty: f32,
    near: f32,
    far: f32,
}

/// One bit per frustum side that camera-frame point `p` lies beyond.
#[inline(always)]
fn outcode(p: [f32; 3], f: &Frustum) -> u8 {
    let [x, y, z] = p;
    (x > f.tx * z) as u8
        | ((x < -f.tx * z) as u8) << 1
        | ((y > f.ty * z) as u8) << 2
        | ((y < -f.ty * z) as u8) << 3
        | ((z < f.near) as u8) << 4
        | ((z > f.far) as u8) << 5
}

/// Clips a camera-frame triangle against the near plane, culls it when it is a back face of a
/// closed shape, and sets up what is left for filling.
#[inline]
fn setup_triangle(out: &mut Vec<Setup>, k: &Projection, t: [[f32; 3]; 3], closed: bool, tri: u32) {
    let [a, b, c] = t;
    let n = cross(sub(b, a), sub(c, a));
    let d = dot(n, a);
    // A front face has its outward normal towards the camera (at the origin): n·a < 0.
    if (closed && d >= 0.0) || d == 0.0 || !d.is_finite() {
        return;
    }
    let near = k.near;
    let inside = [a[2] >= near, b[2] >= near, c[2] >= near];
    if !inside.iter().any(|&x| x) {
        return;
    }
    // 1/z = (n·(rx, ry, 1)) / d with rx = (x − cx)/fx, ry = (y − cy)/fy.
    let inv_d = 1.0 / d;
    let plane = [
        n[0] / k.fx * inv_d,
        n[1] / k.fy * inv_d,
        (n[2] - n[0] * k.cx / k.fx - n[1] * k.cy / k.fy) * inv_d,
    ];
    if inside.iter().all(|&x| x) {
        out.extend(Setup::new(k, [k.project(a), k.project(b), k.project(c)], plane, tri));
        return;
    }
    // Sutherland–Hodgman against z = near: at most four vertices.
    let mut poly = [[0.0f32; 3]; 4];
    let mut len = 0;
    for j in 0..3 {
        let (p, q) = (t[j], t[(j + 1) % 3]);
        let (pin, qin) = (p[2] >= near, q[2] >= near);
        if pin {
            poly[len] = p;
            len += 1;
        }
        if pin != qin {
            let s = (near - p[2]) / (q[2] - p[2]);
            let mut x = lerp(p, q, s);
            x[2] = near;
            poly[len] = x;
            len += 1;
        }
    }
    if len < 3 {
        return;
    }
    let s: [[f32; 2]; 4] = poly.map(|p| if p[2] > 0.0 { k.project(p) } else { [0.0; 2] });
    for j in 1..len - 1 {
        out.extend(Setup::new(k, [s[0], s[j], s[j + 1]], plane, tri));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn proj() -> Projection {
        Projection {
            fx: 4.0,
            fy: 4.0,
            cx: 4.0,
            cy: 4.0,
            near: 0.1,
            width: 8,
            height: 8,
        }
    }

    /// A square at z = 2 facing the camera covers the middle pixels at depth 2; turned away
    /// and closed, it is culled; straddling the near plane, it is clipped, not dropped.
    #[test]
    fn square_fill_cull_and_clip() {
        let k = proj();
        let quad = |z0: f32, z1: f32| {
            let a = [-1.0, -1.0, z0];
            let b = [1.0, -1.0, z0];
            let c = [1.0, 1.0, z1];
            let d = [-1.0, 1.0, z1];
            [[a, d, c], [a, c, b]]
        };
        let draw = |tris: &[([[f32; 3]; 3], bool)]| {
            let mut setups = Vec::new();
            for (n, (tri, closed)) in tris.iter().enumerate() {
                setup_triangle(&mut setups, &k, *tri, *closed, n as u32);
            }
            let (mut inv_z, mut tri) = (vec![0.0f32; 64], vec![NO_ITEM; 64]);
            Band {
                inv_z: &mut inv_z,
                tri: &mut tri,
                first_row: 0,
                rows: 8,
                width: 8,
            }
            .fill_all(&setups, true);
            inv_z
        };
        let t = draw(&quad(2.0, 2.0).map(|q| (q, true)));
        let covered: Vec<usize> = (0..64).filter(|&i| t[i] > 0.0).collect();
        // x/z ∈ [−½, ½] → pixels 2..=5 in u and v.
        assert_eq!(covered.len(), 16, "{covered:?}");
        for &i in &covered {
            assert!((1.0 / t[i] - 2.0).abs() < 1e-5);
            let (u, v) = (i % 8, i / 8);
            assert!((2..=5).contains(&u) && (2..=5).contains(&v));
        }
        // The same square wound the other way is a back face.
        let t = draw(&quad(2.0, 2.0).map(|q| ([q[0], q[2], q[1]], true)));
        assert!(t.iter().all(|&z| z == 0.0));
        // Tilted through the near plane: the far half is drawn, with plane depth.
        let t = draw(&quad(-1.0, 3.0).map(|q| (q, false)));
        let drawn = t.iter().filter(|&&z| z > 0.0).count();
        assert!(drawn > 0);
        for (i, &iz) in t.iter().enumerate() {
            if iz > 0.0 {
                assert!(1.0 / iz >= 0.1 - 1e-4, "pixel {i} at {}", 1.0 / iz);
            }
        }
    }
}
