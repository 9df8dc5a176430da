//! A flat bounding-volume hierarchy over item bounding boxes, built with binned surface-area
//! splits and traversed nearest child first with an explicit stack: the ray caster's hot loop.

use parry3d::math::Vector;

/// Largest number of items in a leaf.
const LEAF_SIZE: usize = 2;
/// Centroid bins per split.
const BINS: usize = 12;
/// Traversal stack depth (the tree depth stays far below this for any realistic scene; deeper
/// subtrees are still visited, just without ordering, see `cast`).
const STACK: usize = 64;

#[derive(Clone, Copy, Debug)]
struct Node {
    min: Vector,
    max: Vector,
    /// Leaf: first index into `order`; interior: index of the left child (right = left + 1).
    first: u32,
    /// Items in a leaf; 0 for interior nodes.
    count: u32,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bounds {
    pub(crate) min: Vector,
    pub(crate) max: Vector,
}

impl Bounds {
    pub(crate) const EMPTY: Bounds = Bounds {
        min: Vector::splat(f32::INFINITY),
        max: Vector::splat(f32::NEG_INFINITY),
    };

    fn grow(&mut self, other: &Bounds) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    fn grow_point(&mut self, p: Vector) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    fn centre(&self) -> Vector {
        (self.min + self.max) * 0.5
    }

    fn area(&self) -> f32 {
        let d = (self.max - self.min).max(Vector::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
}

/// The hierarchy: nodes and the item order leaves index into.
#[derive(Clone, Debug, Default)]
pub(crate) struct FlatBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

/// Entry distance of a ray (origin `o`, inverse direction `inv`) into a box, if it enters
/// before `limit`.
#[inline(always)]
fn slab(min: Vector, max: Vector, o: Vector, inv: Vector, limit: f32) -> Option<f32> {
    let t1 = (min - o) * inv;
    let t2 = (max - o) * inv;
    let near = t1.min(t2).max_element().max(0.0);
    let far = t1.max(t2).min_element().min(limit);
    (near <= far).then_some(near)
}

impl FlatBvh {
    /// Builds over `items` (ids) with bounds `bounds[id]`.
    pub(crate) fn build(items: &[u32], bounds: &[Bounds]) -> Self {
        let mut bvh = FlatBvh::default();
        bvh.rebuild(items, bounds);
        bvh
    }

    /// Rebuilds over `items` in place, reusing the node and order buffers (no allocation once
    /// they are large enough).
    pub(crate) fn rebuild(&mut self, items: &[u32], bounds: &[Bounds]) {
        self.nodes.clear();
        self.order.clear();
        self.order.extend_from_slice(items);
        if items.is_empty() {
            return;
        }
        self.nodes.push(Node {
            min: Vector::ZERO,
            max: Vector::ZERO,
            first: 0,
            count: 0,
        });
        self.split(0, 0, items.len(), bounds);
    }

    /// Makes node `index` cover `order[start..end]`, splitting it while that pays.
    fn split(&mut self, index: usize, start: usize, end: usize, bounds: &[Bounds]) {
        let mut node_bounds = Bounds::EMPTY;
        let mut centres = Bounds::EMPTY;
        for &i in &self.order[start..end] {
            let b = &bounds[i as usize];
            node_bounds.grow(b);
            centres.grow_point(b.centre());
        }
        let n = end - start;
        let leaf = |nodes: &mut Vec<Node>| {
            nodes[index] = Node {
                min: node_bounds.min,
                max: node_bounds.max,
                first: start as u32,
                count: n as u32,
            };
        };
        if n <= LEAF_SIZE {
            leaf(&mut self.nodes);
            return;
        }
        // Binned surface-area heuristic over the widest centroid axis.
        let extent = centres.max - centres.min;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let lo = centres.min[axis];
        let width = extent[axis];
        let mid = if width <= 1e-9 {
            // Every centre coincides: split the list in half.
            start + n / 2
        } else {
            let bin_of = |b: &Bounds| (((b.centre()[axis] - lo) / width * BINS as f32) as usize).min(BINS - 1);
            let mut bin_bounds = [Bounds::EMPTY; BINS];
            let mut bin_count = [0usize; BINS];
            for &i in &self.order[start..end] {
                let b = &bounds[i as usize];
                let k = bin_of(b);
                bin_bounds[k].grow(b);
                bin_count[k] += 1;
            }
            let mut best = (f32::INFINITY, 0);
            for cut in 1..BINS {
                let (mut l, mut r) = (Bounds::EMPTY, Bounds::EMPTY);
                let (mut nl, mut nr) = (0, 0);
                for k in 0..cut {
                    l.grow(&bin_bounds[k]);
                    nl += bin_count[k];
                }
                for k in cut..BINS {
                    r.grow(&bin_bounds[k]);
                    nr += bin_count[k];
                }
                if nl == 0 || nr == 0 {
                    continue;
                }
                let cost = l.area() * nl as f32 + r.area() * nr as f32;
                if cost < best.0 {
                    best = (cost, cut);
                }
            }
            if best.1 == 0 {
                start + n / 2
            } else {
                let cut = best.1;
                let slice = &mut self.order[start..end];
                let mut i = 0;
                for j in 0..slice.len() {
                    if bin_of(&bounds[slice[j] as usize]) < cut {
                        slice.swap(i, j);
                        i += 1;
                    }
                }
                start + i
            }
        };
        let mid = if mid == start || mid == end { start + n / 2 } else { mid };
        let left = self.nodes.len();
        let blank = Node {
            min: Vector::ZERO,
            max: Vector::ZERO,
            first: 0,
            count: 0,
        };
        self.nodes.push(blank);
        self.nodes.push(blank);
        self.nodes[index] = Node {
            min: node_bounds.min,
            max: node_bounds.max,
            first: left as u32,
            count: 0,
        };
        self.split(left, start, mid, bounds);
        self.split(left + 1, mid, end, bounds);
    }

    /// Closest hit along the ray within `limit`: `leaf(item, best_so_far)` tests one item and
    /// returns its hit distance when closer than `best_so_far`. Returns the best distance and
    /// item.
    #[inline]
    pub(crate) fn cast(
        &self,
        o: Vector,
        inv: Vector,
        limit: f32,
        mut leaf: impl FnMut(u32, f32) -> Option<f32>,
    ) -> Option<(f32, u32)> {
        let root = self.nodes.first()?;
        slab(root.min, root.max, o, inv, limit)?;
        let mut best = limit;
        let mut found = None;
        let mut stack = [(0u32, 0.0f32); STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (index, entry) = stack[top];
            if entry > best {
                continue;
            }
            let node = self.nodes[index as usize];
            if node.count > 0 {
                let first = node.first as usize;
                for &item in &self.order[first..first + node.count as usize] {
                    if let Some(t) = leaf(item, best)
                        && t < best
                    {
                        best = t;
                        found = Some(item);
                    }
                }
                continue;
            }
            let (a, b) = (node.first, node.first + 1);
            let na = &self.nodes[a as usize];
            let nb = &self.nodes[b as usize];
            let ta = slab(na.min, na.max, o, inv, best);
            let tb = slab(nb.min, nb.max, o, inv, best);
            // Push the farther child first so the nearer one is popped next.
            let mut push = |i: u32, t: f32| {
                if top < STACK {
                    stack[top] = (i, t);
                    top += 1;
                } else {
                    // Out of stack: test the subtree right away, unordered.
                    self.visit(i, o, inv, &mut best, &mut found, &mut leaf);
                }
            };
            match (ta, tb) {
                (Some(x), Some(y)) if x <= y => {
                    push(b, y);
                    push(a, x);
                }
                (Some(x), Some(y)) => {
                    push(a, x);
                    push(b, y);
                }
                (Some(x), None) => push(a, x),
                (None, Some(y)) => push(b, y),
                (None, None) => {}
            }
        }
        found.map(|item| (best, item))
    }

    /// Recursive fallback for subtrees deeper than the stack.
    fn visit(
        &self,
        index: u32,
        o: Vector,
        inv: Vector,
        best: &mut f32,
        found: &mut Option<u32>,
        leaf: &mut impl FnMut(u32, f32) -> Option<f32>,
    ) {
        let node = self.nodes[index as usize];
        if slab(node.min, node.max, o, inv, *best).is_none() {
            return;
        }
        if node.count > 0 {
            let first = node.first as usize;
            for &item in &self.order[first..first + node.count as usize] {
                if let Some(t) = leaf(item, *best)
                    && t < *best
                {
                    *best = t;
                    *found = Some(item);
                }
            }
        } else {
            self.visit(node.first, o, inv, best, found, leaf);
            self.visit(node.first + 1, o, inv, best, found, leaf);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit boxes along x at 0, 3, 6, …: a ray along +x from −5 hits the first, along −x from
    /// far away the last.
    #[test]
    fn closest_box_along_a_row() {
        let bounds: Vec<Bounds> = (0..100)
            .map(|i| {
                let c = Vector::new(3.0 * i as f32, 0.0, 0.0);
                Bounds {
                    min: c - Vector::splat(0.5),
                    max: c + Vector::splat(0.5),
                }
            })
            .collect();
        let items: Vec<u32> = (0..100).collect();
        let bvh = FlatBvh::build(&items, &bounds);
        let hit_box = |o: Vector, d: Vector| {
            let inv = Vector::ONE / d;
            bvh.cast(o, inv, 1e4, |i, best| {
                let b = &bounds[i as usize];
                slab(b.min, b.max, o, inv, best)
            })
        };
        let (t, item) = hit_box(Vector::new(-5.0, 0.0, 0.0), Vector::X).unwrap();
        assert_eq!(item, 0);
        assert!((t - 4.5).abs() < 1e-5);
        let (t, item) = hit_box(Vector::new(400.0, 0.0, 0.0), -Vector::X).unwrap();
        assert_eq!(item, 99);
        assert!((t - (400.0 - 297.5)).abs() < 1e-3);
        assert!(hit_box(Vector::new(0.0, 5.0, 0.0), Vector::X).is_none());
        assert!(
            FlatBvh::build(&[], &bounds)
                .cast(Vector::ZERO, Vector::ONE, 1.0, |_, _| None)
                .is_none()
        );
    }
}
