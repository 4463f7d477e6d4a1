//! The flattened BVH and triangle layout that the CPU tracer walks and a WGSL tracer can read as
//! two storage buffers, unchanged.
//!
//! The tree is built by [`obvhs`] (a binned-SAH PLOC builder with reinsertion; Meister and
//! Bittner 2018, "Parallel Locally-Ordered Clustering for Bounding Volume Hierarchy
//! Construction", and Meister and Bittner 2018, "Parallel Reinsertion for Bounding Volume
//! Hierarchy Optimization"; [`REINSERTION_BATCH_RATIO`]) and copied node by node into
//! [`BvhNode`]: node 0 is the root; an inner node's
//! children are `nodes[index]` and `nodes[index + 1]`; a leaf covers `triangles[index ..
//! index + count]`. The triangles are stored in leaf order, so a leaf needs no index
//! indirection. [`Bvh::intersect`], [`Bvh::intersect_front`] and [`Bvh::occluded`] are written
//! the way a shader walks the tree — one fixed-size stack of node indices, nearer child first —
//! so the WGSL twin is a line-by-line port.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2_from_tris};

/// The share of the nodes obvhs's reinsertion optimiser reconsiders, per pass (its medium
/// preset's 0.05 raised; [`BvhBuildParams::reinsertion_batch_ratio`]).
///
/// PLOC pairs clusters that lie near each other along a Morton curve. Over surfaces tiled
/// by many small coplanar triangles, as architecture is, its medium preset left trees that a
/// ray walks for ~8× what a top-down binned SAH tree costs: the built-in rooms split into
/// 98,306 triangles (`render --subdivide 5`) gave an SAH cost ([`Bvh::sah_cost`]) of 304
/// node visits and triangle tests per ray, 249 nodes and 140 triangles per walk measured,
/// against 37 (24 and 2) for a binned SAH build. Reinsertion repairs it: at 2 the cost is
/// 41 (23 nodes and 5 triangles per walk), for a build of 0.29 s instead of 0.03 s on one
/// core; at 1, 54 (37 and 7) in 0.22 s; above 2 it gains little (4: 40, in 0.42 s). The
/// built-in rooms as committed (98 triangles) cost 13.2 instead of 14.8. obvhs's `parallel`
/// feature (on) spreads the build over rayon's threads: 0.18 s on two cores, the same tree
/// node for node whatever the thread count.
pub const REINSERTION_BATCH_RATIO: f32 = 2.0;

/// One node of the flattened BVH: 32 bytes, two `vec4`s in WGSL
/// (`struct BvhNode { min: vec3f, index: u32, max: vec3f, count: u32 }`).
///
/// `count == 0` marks an inner node whose children are `index` and `index + 1`; otherwise the
/// node is a leaf over `count` triangles starting at `index`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// The lower corner of the node's box.
    pub min: [f32; 3],
    /// First child (inner node) or first triangle (leaf).
    pub index: u32,
    /// The upper corner of the node's box.
    pub max: [f32; 3],
    /// Number of triangles of a leaf; 0 for an inner node.
    pub count: u32,
}

/// One triangle, 48 bytes (three `vec4`s in WGSL): a vertex, two edge vectors, its material and
/// the probability that light sampling picks it.
///
/// The geometric normal `e1 × e2` points to the front face (counter-clockwise winding, as glTF
/// defines), the only face that emits.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Triangle {
    /// The first vertex, in world space (metres).
    pub v0: [f32; 3],
    /// Index into the scene's materials.
    pub material: u32,
    /// `v1 − v0`.
    pub e1: [f32; 3],
    /// Probability with which light sampling picks this triangle (0 for non-emitters); the
    /// integrator needs it for the MIS weight of an emitter hit by a BSDF-sampled ray.
    pub emitter_pmf: f32,
    /// `v2 − v0`.
    pub e2: [f32; 3],
    /// In the emitters' tree ([`Scene::emitter_bvh`](super::scene::Scene::emitter_bvh)), the
    /// index of the same triangle in the scene's tree (whose texture coordinates it takes);
    /// 0 elsewhere.
    pub source: u32,
}

impl Triangle {
    /// The triangle with corners `v0, v1, v2` and material `material` (not an emitter yet).
    #[must_use]
    pub fn new(v0: Vec3, v1: Vec3, v2: Vec3, material: u32) -> Self {
        Self {
            v0: v0.to_array(),
            material,
            e1: (v1 - v0).to_array(),
            emitter_pmf: 0.0,
            e2: (v2 - v0).to_array(),
            source: 0,
        }
    }

    /// The unnormalised geometric normal `e1 × e2` (length = twice the area), front side.
    #[must_use]
    pub fn cross(&self) -> Vec3 {
        Vec3::from(self.e1).cross(Vec3::from(self.e2))
    }

    /// The area in square metres.
    #[must_use]
    pub fn area(&self) -> f32 {
        0.5 * self.cross().length()
    }

    /// The point at barycentric coordinates `(b1, b2)` (weights of `v1` and `v2`).
    #[must_use]
    pub fn point(&self, b1: f32, b2: f32) -> Vec3 {
        Vec3::from(self.v0) + b1 * Vec3::from(self.e1) + b2 * Vec3::from(self.e2)
    }

    /// Möller–Trumbore ray/triangle test (Möller and Trumbore 1997, "Fast, Minimum Storage
    /// Ray/Triangle Intersection"): the distance `t` in `(t_min, t_max)` along the unit
    /// `direction` and the barycentric coordinates `(b1, b2)` of the hit (weights of `v1` and
    /// `v2`), or `None`. Both faces are hit.
    #[inline]
    #[must_use]
    pub fn intersect(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        self.intersect_faces::<false>(origin, direction, t_min, t_max)
    }

    /// [`intersect`](Self::intersect) for the front face only (the face `e1 × e2` points to,
    /// the one that emits): a ray that meets the back face misses.
    #[inline]
    #[must_use]
    pub fn intersect_front(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        self.intersect_faces::<true>(origin, direction, t_min, t_max)
    }

    /// Möller–Trumbore with both faces or, with `FRONT`, the front face only: the determinant
    /// `e1 · (d × e2) = −d · (e1 × e2)` is positive exactly when the ray meets the front face.
    #[inline]
    fn intersect_faces<const FRONT: bool>(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        let e1 = Vec3::from(self.e1);
        let e2 = Vec3::from(self.e2);
        let p = direction.cross(e2);
        let det = e1.dot(p);
        if (if FRONT { det } else { det.abs() }) < 1e-12 {
            return None;
        }
        let inv = 1.0 / det;
        let s = origin - Vec3::from(self.v0);
        let b1 = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&b1) {
            return None;
        }
        let q = s.cross(e1);
        let b2 = direction.dot(q) * inv;
        if b2 < 0.0 || b1 + b2 > 1.0 {
            return None;
        }
        let t = e2.dot(q) * inv;
        (t > t_min && t < t_max).then_some((t, b1, b2))
    }
}

/// The closest hit of a ray: the distance and the triangle's index in [`Bvh::triangles`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the unit ray direction, in metres.
    pub t: f32,
    /// Index of the triangle in [`Bvh::triangles`] (leaf order).
    pub triangle: u32,
    /// Barycentric weight of the triangle's `v1` at the hit.
    pub b1: f32,
    /// Barycentric weight of the triangle's `v2` at the hit.
    pub b2: f32,
}

/// Depth of the traversal stack: [`Bvh::intersect`] and [`Bvh::occluded`] need a tree of
/// [`Bvh::depth`] at most `STACK_SIZE` (the scene loader reports a deeper one as an error;
/// PLOC trees over millions of triangles stay far below it).
pub const STACK_SIZE: usize = 64;

/// A BVH over triangles in the flattened layout of this module.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// The nodes; node 0 is the root.
    pub nodes: Vec<BvhNode>,
    /// The triangles in leaf order.
    pub triangles: Vec<Triangle>,
    /// For each entry of `triangles`, its index in the builder's input (to reorder data kept
    /// beside the triangles, such as texture coordinates).
    pub source: Vec<u32>,
}

impl Bvh {
    /// Builds the tree over `triangles` with obvhs's medium-quality preset (no spatial splits,
    /// so every triangle appears in exactly one leaf) and reorders them into leaf order.
    /// Returns an empty BVH for no triangles.
    #[must_use]
    pub fn build(triangles: &[Triangle]) -> Self {
        if triangles.is_empty() {
            return Self::default();
        }
        let tris: Vec<obvhs::triangle::Triangle> = triangles
            .iter()
            .map(|t| {
                let v0 = glam::Vec3A::from_array(t.v0);
                obvhs::triangle::Triangle {
                    v0,
                    v1: v0 + glam::Vec3A::from_array(t.e1),
                    v2: v0 + glam::Vec3A::from_array(t.e2),
                }
            })
            .collect();
        let mut params = BvhBuildParams::medium_build();
        params.pre_split = false;
        params.reinsertion_batch_ratio = REINSERTION_BATCH_RATIO;
        let bvh2 = build_bvh2_from_tris(&tris, params, &mut core::time::Duration::default());
        let nodes = bvh2
            .nodes
            .iter()
            .map(|n| BvhNode {
                min: n.aabb.min.to_array(),
                index: n.first_index,
                max: n.aabb.max.to_array(),
                count: n.prim_count,
            })
            .collect();
        let source = bvh2.primitive_indices;
        let triangles = source.iter().map(|&i| triangles[i as usize]).collect();
        Self {
            nodes,
            triangles,
            source,
        }
    }

    /// The leaf-order index of each input triangle, in input order (the inverse of
    /// [`Bvh::source`]): `triangles[input_order()[i]]` is the builder's `i`-th input.
    #[must_use]
    pub fn input_order(&self) -> Vec<usize> {
        let mut order = vec![0; self.source.len()];
        for (leaf, &input) in self.source.iter().enumerate() {
            order[input as usize] = leaf;
        }
        order
    }

    /// The tree's surface-area-heuristic cost (MacDonald and Booth 1990, "Heuristics for ray
    /// tracing using space subdivision"): Σ over inner nodes of their box's area plus Σ over
    /// leaves of their box's area times their triangles, over the root box's area. For rays
    /// that cross the root box uniformly at random, the expected number of box tests' nodes
    /// walked plus triangles tested; a measure of the tree's quality (lower is better) that
    /// needs no rays. 0 when empty.
    #[must_use]
    pub fn sah_cost(&self) -> f32 {
        let area = |n: &BvhNode| {
            let d = (Vec3::from(n.max) - Vec3::from(n.min)).max(Vec3::ZERO);
            2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
        };
        let Some(root) = self.nodes.first().map(area).filter(|&a| a > 0.0) else {
            return 0.0;
        };
        let sum: f32 = self
            .nodes
            .iter()
            .map(|n| area(n) * if n.count > 0 { n.count as f32 } else { 1.0 })
            .sum();
        sum / root
    }

    /// The depth of the tree (1 for a root leaf, 0 when empty).
    #[must_use]
    pub fn depth(&self) -> usize {
        fn walk(nodes: &[BvhNode], i: usize) -> usize {
            let n = nodes[i];
            if n.count > 0 {
                1
            } else {
                1 + walk(nodes, n.index as usize).max(walk(nodes, n.index as usize + 1))
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            walk(&self.nodes, 0)
        }
    }

    /// The closest triangle hit by the ray `origin + t·direction`, `t ∈ (t_min, t_max)`.
    #[must_use]
    pub fn intersect(&self, origin: Vec3, direction: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        self.closest::<false>(origin, direction, t_min, t_max, |_, _, _| true)
    }

    /// [`intersect`](Self::intersect) where a hit on triangle `i` at barycentrics
    /// `(b1, b2)` counts only if `keep(i, b1, b2)` (alpha-masked surfaces, which rays pass
    /// where they are cut out).
    #[must_use]
    pub fn intersect_where(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
        keep: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        self.closest::<false>(origin, direction, t_min, t_max, keep)
    }

    /// The closest triangle whose front face the ray `origin + t·direction` meets, `t ∈
    /// (t_min, t_max)`; back faces are not hit (they neither count nor block).
    #[must_use]
    pub fn intersect_front(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<Hit> {
        self.closest::<true>(origin, direction, t_min, t_max, |_, _, _| true)
    }

    /// [`intersect_front`](Self::intersect_front) with the hits that `keep` refuses passed
    /// through, as [`intersect_where`](Self::intersect_where).
    #[must_use]
    pub fn intersect_front_where(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
        keep: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        self.closest::<true>(origin, direction, t_min, t_max, keep)
    }

    /// The closest hit of both faces or, with `FRONT`, of front faces only, among those that
    /// `keep` accepts.
    fn closest<const FRONT: bool>(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
        keep: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_far = t_max;
        let on_hit = |i, (t, b1, b2)| {
            best = Some(Hit {
                t,
                triangle: i,
                b1,
                b2,
            });
            false
        };
        self.walk::<FRONT>(origin, direction, t_min, &mut t_far, keep, on_hit);
        best
    }

    /// Whether any triangle blocks the ray within `(t_min, t_max)` (shadow rays).
    #[must_use]
    pub fn occluded(&self, origin: Vec3, direction: Vec3, t_min: f32, t_max: f32) -> bool {
        self.occluded_where(origin, direction, t_min, t_max, |_, _, _| true)
    }

    /// [`occluded`](Self::occluded) where only the hits that `keep` accepts block, as
    /// [`intersect_where`](Self::intersect_where).
    #[must_use]
    pub fn occluded_where(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
        keep: impl Fn(u32, f32, f32) -> bool,
    ) -> bool {
        let mut hit = false;
        let mut t_far = t_max;
        self.walk::<false>(origin, direction, t_min, &mut t_far, keep, |_, _| {
            hit = true;
            true
        });
        hit
    }

    /// The stack walk shared by both queries: `on_hit(triangle, (t, b1, b2))` is called for
    /// each hit closer than `t_far` that `keep(triangle, b1, b2)` accepts (`t_far` then shrinks
    /// to `t`) and stops the walk by returning `true`. With `FRONT`, only front faces are hit.
    fn walk<const FRONT: bool>(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_far: &mut f32,
        keep: impl Fn(u32, f32, f32) -> bool,
        mut on_hit: impl FnMut(u32, (f32, f32, f32)) -> bool,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = direction.recip();
        // Front-face queries gather emission from a small tree of emitters that most of
        // their rays miss: the root's box turns those away before the walk starts.
        if FRONT && box_entry(&self.nodes[0], origin, inv, t_min, *t_far) == f32::INFINITY {
            return;
        }
        let mut stack = [0u32; STACK_SIZE];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if node.count > 0 {
                for i in node.index..node.index + node.count {
                    if let Some(hit) = self.triangles[i as usize]
                        .intersect_faces::<FRONT>(origin, direction, t_min, *t_far)
                        .filter(|&(_, b1, b2)| keep(i, b1, b2))
                    {
                        *t_far = hit.0;
                        if on_hit(i, hit) {
                            return;
                        }
                    }
                }
                continue;
            }
            let a = node.index;
            let ta = box_entry(&self.nodes[a as usize], origin, inv, t_min, *t_far);
            let tb = box_entry(&self.nodes[a as usize + 1], origin, inv, t_min, *t_far);
            // Push the farther child first so that the nearer one is popped next.
            let (near, far, t_near, t_farther) = if ta <= tb {
                (a, a + 1, ta, tb)
            } else {
                (a + 1, a, tb, ta)
            };
            if t_farther < f32::INFINITY {
                stack[top] = far;
                top += 1;
            }
            if t_near < f32::INFINITY {
                stack[top] = near;
                top += 1;
            }
        }
    }
}

/// The entry distance of the ray into the node's box (slab test, Kay and Kajiya 1986), or +∞
/// when it misses the box within `(t_min, t_max)`. `inv` is `1 / direction` per axis.
#[inline]
fn box_entry(node: &BvhNode, origin: Vec3, inv: Vec3, t_min: f32, t_max: f32) -> f32 {
    let t0 = (Vec3::from(node.min) - origin) * inv;
    let t1 = (Vec3::from(node.max) - origin) * inv;
    let enter = t0.min(t1).max_element().max(t_min);
    let exit = t0.max(t1).min_element().min(t_max);
    if enter <= exit { enter } else { f32::INFINITY }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> Vec<Triangle> {
        // n×n unit quads in the z = 0 plane, plus a parallel plane at z = 1, two triangles each.
        let mut out = Vec::new();
        for z in [0.0, 1.0] {
            for i in 0..n {
                for j in 0..n {
                    let p = Vec3::new(i as f32, j as f32, z);
                    let m = (i * n + j) as u32;
                    out.push(Triangle::new(p, p + Vec3::X, p + Vec3::X + Vec3::Y, m));
                    out.push(Triangle::new(p, p + Vec3::X + Vec3::Y, p + Vec3::Y, m));
                }
            }
        }
        out
    }

    /// Hypothesis: the BVH walk finds exactly the closest hit (and the closest front-face hit)
    /// of a brute-force loop over all triangles, for 2000 rays of fixed seed through a 2×16×16-quad scene (any difference
    /// fails), and every triangle sits in exactly one leaf.
    #[test]
    fn walk_matches_brute_force() {
        let tris = grid(16);
        let bvh = Bvh::build(&tris);
        assert_eq!(bvh.triangles.len(), tris.len());
        let mut seen = vec![0u32; tris.len()];
        for n in &bvh.nodes {
            for i in n.index..n.index + n.count {
                seen[i as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
        assert!(bvh.depth() < STACK_SIZE);
        let mut state = 12345u32;
        let mut u = || mcg_gpu_backend::sampling::next_uniform(&mut state);
        let (mut hits, mut fronts) = (0, 0);
        for _ in 0..2000 {
            let origin = Vec3::new(u() * 20.0 - 2.0, u() * 20.0 - 2.0, u() * 3.0 - 1.0);
            let direction = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
            let brute = bvh
                .triangles
                .iter()
                .enumerate()
                .filter_map(|(i, t)| {
                    t.intersect(origin, direction, 1e-4, f32::INFINITY)
                        .map(|h| (h.0, i as u32))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let fast = bvh.intersect(origin, direction, 1e-4, f32::INFINITY);
            assert_eq!(fast.map(|h| h.t), brute.map(|b| b.0));
            let brute_front = bvh
                .triangles
                .iter()
                .filter_map(|t| t.intersect_front(origin, direction, 1e-4, f32::INFINITY))
                .map(|h| h.0)
                .min_by(f32::total_cmp);
            let front = bvh.intersect_front(origin, direction, 1e-4, f32::INFINITY);
            assert_eq!(front.map(|h| h.t), brute_front);
            if let Some(h) = front {
                let n = bvh.triangles[h.triangle as usize].cross();
                assert!(n.dot(direction) < 0.0, "a front hit meets the front face");
            }
            fronts += usize::from(front.map(|h| h.t) != fast.map(|h| h.t));
            assert_eq!(
                bvh.occluded(origin, direction, 1e-4, f32::INFINITY),
                brute.is_some()
            );
            hits += usize::from(brute.is_some());
        }
        assert!(
            hits > 200 && fronts > 50,
            "the test rays must hit often enough to decide: {hits} hits, {fronts} with a back \
             face nearest"
        );
    }
}
