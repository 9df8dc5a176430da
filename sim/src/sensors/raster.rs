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
use super::gpu::tessellate::{ItemRange, tessellate};
use super::visuals::VisualScene;

/// Item id of a pixel that sees nothing.
const NO_ITEM: u32 = u32::MAX;

/// The modalities [`RasterCamera`] renders.
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

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn lerp(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// The z-buffer and the triangle fill.
#[derive(Clone, Debug, Default)]
struct Target {
    /// Per pixel: 1/z of the nearest surface so far (0: nothing).
    inv_z: Vec<f32>,
    /// Per pixel: the index of the triangle that wrote it (into the index buffer, /3).
    tri: Vec<u32>,
}

impl Target {
    fn clear(&mut self, pixels: usize) {
        self.inv_z.clear();
        self.inv_z.resize(pixels, 0.0);
        self.tri.clear();
        self.tri.resize(pixels, NO_ITEM);
    }

    /// Fills the screen triangle `s` (pixel coordinates) where the plane's 1/z (`plane`:
    /// 1/z = a·x + b·y + c at pixel centre (x, y)) is nearer than what is there.
    #[inline]
    fn fill(&mut self, k: &Projection, s: [[f32; 2]; 3], plane: [f32; 3], tri: u32) {
        let [p0, p1, p2] = s;
        let area = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
        if !(area.abs() > 1e-12) {
            return;
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
            return;
        }
        let u0 = (xmin - 0.5).ceil().max(0.0) as usize;
        let u1 = ((xmax - 0.5).floor().min(w - 1.0)) as usize;
        let v0 = (ymin - 0.5).ceil().max(0.0) as usize;
        let v1 = ((ymax - 0.5).floor().min(h - 1.0)) as usize;
        if u0 > u1 || v0 > v1 {
            return;
        }
        // Edge functions e(x, y) = A x + B y + C, ≥ 0 inside.
        let edge = |a: [f32; 2], b: [f32; 2]| {
            let ea = a[1] - b[1];
            let eb = b[0] - a[0];
            [ea, eb, a[0] * b[1] - a[1] * b[0]]
        };
        let e = [edge(p0, p1), edge(p1, p2), edge(p2, p0)];
        let [pa, pb, pc] = plane;
        let width = k.width;
        for v in v0..=v1 {
            let y = v as f32 + 0.5;
            // The span of the row inside all three edges.
            let (mut lo, mut hi) = (u0 as f32 + 0.5, u1 as f32 + 0.5);
            let mut empty = false;
            for [ea, eb, ec] in e {
                let r = eb * y + ec;
                if ea > 0.0 {
                    lo = lo.max(-r / ea);
                } else if ea < 0.0 {
                    hi = hi.min(-r / ea);
                } else if r < 0.0 {
                    empty = true;
                }
            }
            if empty || lo > hi {
                continue;
            }
            let a = (lo - 0.5).ceil().max(u0 as f32);
            let b = (hi - 0.5).floor().min(u1 as f32);
            if a > b {
                continue;
            }
            let (a, b) = (a as usize, b as usize);
            let row = v * width;
            let base = pb * y + pc;
            for u in a..=b {
                let x = u as f32 + 0.5;
                // Inside test at the exact centre (the span bounds may round either way).
                if e.iter().any(|[ea, eb, ec]| ea * x + eb * y + ec < 0.0) {
                    continue;
                }
                let iz = pa * x + base;
                let i = row + u;
                if iz > self.inv_z[i] {
                    self.inv_z[i] = iz;
                    self.tri[i] = tri;
                }
            }
        }
    }
}

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
    /// Scratch: the z-buffer.
    target: Target,
    /// Items drawn in the last frame.
    drawn: usize,
}

impl RasterCamera {
    /// A rasteriser over `scene`'s shapes and ids.
    ///
    /// # Errors
    /// [`SensorError::InvalidResolution`] / [`SensorError::InvalidParameter`] for bad intrinsics.
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
            indices: mesh.indices,
            ranges: mesh.ranges,
            vertex_ranges,
            tri_item,
            ids: scene.items.iter().map(|i| (i.semantic, i.instance)).collect(),
            target: Target::default(),
            drawn: 0,
        })
    }

    /// The intrinsics.
    pub fn intrinsics(&self) -> &CameraIntrinsics {
        &self.intrinsics
    }

    /// Number of triangles of the tessellated scene.
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }

    /// How many items passed the frustum test in the last frame.
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
        self.target.clear(k.pixels());
        let cam_inv = camera.inverse();
        let (tx, ty) = (k.width as f64 / 2.0 / k.fx(), k.height as f64 / 2.0 / k.fy());
        let (sx, sy) = ((1.0 + tx * tx).sqrt(), (1.0 + ty * ty).sqrt());
        self.drawn = 0;
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
            for (dst, p) in self.cam_vertices[v0 as usize..v1 as usize]
                .iter_mut()
                .zip(&self.positions[v0 as usize..v1 as usize])
            {
                *dst = [
                    m[(0, 0)] * p[0] + m[(0, 1)] * p[1] + m[(0, 2)] * p[2] + m[(0, 3)],
                    m[(1, 0)] * p[0] + m[(1, 1)] * p[1] + m[(1, 2)] * p[2] + m[(1, 3)],
                    m[(2, 0)] * p[0] + m[(2, 1)] * p[1] + m[(2, 2)] * p[2] + m[(2, 3)],
                ];
            }
            let first = r.first_index as usize;
            for t in (first..first + r.index_count as usize).step_by(3) {
                let tri =
                    [self.indices[t], self.indices[t + 1], self.indices[t + 2]].map(|v| self.cam_vertices[v as usize]);
                draw_triangle(&mut self.target, &proj, tri, r.closed, (t / 3) as u32);
            }
        }
        self.resolve(&proj, modalities, frame);
        Ok(())
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
        for v in 0..k.height {
            let ry = (v as f32 + 0.5 - k.cy) / k.fy;
            for u in 0..k.width {
                let i = v * k.width + u;
                let iz = self.target.inv_z[i];
                let z = if iz > 0.0 { 1.0 / iz } else { 0.0 };
                let seen = iz > 0.0 && z >= near && z <= far;
                let z = if seen { z } else { 0.0 };
                if depth {
                    frame.depth[i] = z;
                }
                if pc {
                    let rx = (u as f32 + 0.5 - k.cx) / k.fx;
                    frame.pc[i] = [rx * z, ry * z, z];
                }
                if normal {
                    frame.normal[i] = if seen {
                        self.normal_of(self.target.tri[i])
                    } else {
                        [0.0; 3]
                    };
                }
                let (s, n) = if seen {
                    self.ids[self.tri_item[self.target.tri[i] as usize] as usize]
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

/// Clips a camera-frame triangle against the near plane, culls it when it is a back face of a
/// closed shape, and fills what is left.
#[inline]
fn draw_triangle(target: &mut Target, k: &Projection, t: [[f32; 3]; 3], closed: bool, tri: u32) {
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
    let plane = [
        n[0] / (k.fx * d),
        n[1] / (k.fy * d),
        (n[2] - n[0] * k.cx / k.fx - n[1] * k.cy / k.fy) / d,
    ];
    if inside.iter().all(|&x| x) {
        target.fill(k, [k.project(a), k.project(b), k.project(c)], plane, tri);
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
        target.fill(k, [s[0], s[j], s[j + 1]], plane, tri);
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
        let mut t = Target::default();
        t.clear(64);
        for (n, tri) in quad(2.0, 2.0).into_iter().enumerate() {
            draw_triangle(&mut t, &k, tri, true, n as u32);
        }
        let covered: Vec<usize> = (0..64).filter(|&i| t.inv_z[i] > 0.0).collect();
        // x/z ∈ [−½, ½] → pixels 2..=5 in u and v.
        assert_eq!(covered.len(), 16, "{covered:?}");
        for &i in &covered {
            assert!((1.0 / t.inv_z[i] - 2.0).abs() < 1e-5);
            let (u, v) = (i % 8, i / 8);
            assert!((2..=5).contains(&u) && (2..=5).contains(&v));
        }
        // The same square wound the other way is a back face.
        let mut t = Target::default();
        t.clear(64);
        for tri in quad(2.0, 2.0) {
            draw_triangle(&mut t, &k, [tri[0], tri[2], tri[1]], true, 0);
        }
        assert!(t.inv_z.iter().all(|&z| z == 0.0));
        // Tilted through the near plane: the far half is drawn, with plane depth.
        let mut t = Target::default();
        t.clear(64);
        for tri in quad(-1.0, 3.0) {
            draw_triangle(&mut t, &k, tri, false, 0);
        }
        let drawn = t.inv_z.iter().filter(|&&z| z > 0.0).count();
        assert!(drawn > 0);
        for (i, &iz) in t.inv_z.iter().enumerate() {
            if iz > 0.0 {
                assert!(1.0 / iz >= 0.1 - 1e-4, "pixel {i} at {}", 1.0 / iz);
            }
        }
    }
}
