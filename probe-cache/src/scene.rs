//! A small CPU scene to drive a probe grid: axis-aligned boxes and spheres with analytic ray
//! intersection, one rectangular area light, and one dynamic event (a door that opens or the
//! light that switches on).
//!
//! It stands in for a renderer's ray tracer in tests, examples and the demo. A probe ray sees
//! **one bounce** of light ([`Scene::trace_probe_ray`]):
//!
//! L(x, ω) = L_e            if the ray hits the light's front face,
//! L(x, ω) = ρ/π · E_d(y)   at the first surface hit y with albedo ρ,
//!
//! where E_d(y) is the direct irradiance from the light at y, estimated with one light sample
//! and a shadow ray ([`Scene::direct_irradiance`]). This is the light field ADGI's probes cache
//! (sec. 3.4, g_r) truncated after the first bounce: enough to make a door that opens change
//! the probes near it, and cheap enough to compute a reference with many rays per texel.
//! Back-face hits (a ray that starts inside geometry) return no radiance, as DDGI's probe
//! classification expects.
//!
//! The default scene ([`DynamicScene::door_opens`]) is two rooms side by side: a lit 8 m main
//! room with the light on its ceiling, and a dark 0.9 m closet behind a partition wall whose
//! doorway a sliding door closes until the event frame. When the door slides open, light falls
//! through the doorway into the closet: the probes there and near the door change, the rest of
//! the grid hardly does — the localised change ADGI's guide is built to find (Fig. 1 and 8 of the
//! paper show the same event: a gate that opens in a tunnel).

use std::vec::Vec;

use glam::{UVec3, Vec2, Vec3};

use crate::ProbeGrid;

/// Rays that hit nothing report this distance.
pub const MISS_DISTANCE: f32 = 1.0e4;

/// Rays start this far from the surface they leave, and shadow rays stop this far from their
/// target, so that a surface never shadows itself.
pub const RAY_EPSILON: f32 = 1.0e-4;

/// An axis-aligned box `[min, max]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lowest corner.
    pub min: Vec3,
    /// Highest corner (each component ≥ `min`'s).
    pub max: Vec3,
}

impl Aabb {
    /// The box between `min` and `max`.
    #[must_use]
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The centre of the box.
    #[must_use]
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Whether `p` lies inside the box or on its boundary.
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// The first intersection of the ray `origin + t·dir` with the box's surface for
    /// `t_min < t < t_max`: the distance `t` and the outward normal of the face hit. A ray that
    /// starts inside the box hits the face it leaves through (a back face).
    ///
    /// Slab method (Kay and Kajiya 1986): the ray is inside the slab of axis i for t between
    /// (min_i − o_i)/d_i and (max_i − o_i)/d_i; the box is the intersection of the three slabs.
    #[inline]
    #[must_use]
    pub fn intersect(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, Vec3)> {
        let inv = dir.recip();
        let t0 = (self.min - origin) * inv;
        let t1 = (self.max - origin) * inv;
        let near = t0.min(t1);
        let far = t0.max(t1);
        // Components where dir is 0 give ±∞ (or NaN when the origin is on the slab's plane);
        // `max_element`/`min_element` skip NaN by glam's f32::max semantics.
        let t_near = near.max_element();
        let t_far = far.min_element();
        if !(t_near <= t_far) {
            return None;
        }
        let (t, axis_of) = if t_near > t_min {
            (t_near, near)
        } else if t_far > t_min {
            (t_far, far)
        } else {
            return None;
        };
        if !(t < t_max) {
            return None;
        }
        // The normal is the axis whose slab boundary is at t, pointing out of the box.
        let axis = if axis_of.x == t {
            0
        } else if axis_of.y == t {
            1
        } else {
            2
        };
        let p = origin[axis] + t * dir[axis];
        let sign = if (p - self.min[axis]).abs() < (p - self.max[axis]).abs() {
            -1.0
        } else {
            1.0
        };
        let mut normal = Vec3::ZERO;
        normal[axis] = sign;
        Some((t, normal))
    }
}

/// A sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
}

impl Sphere {
    /// The first intersection of the ray `origin + t·dir` (`dir` of unit length) with the
    /// sphere for `t_min < t < t_max`: the distance and the outward normal at the hit.
    ///
    /// Solves |o + t·d − c|² = r² with the numerically stable form b' = (o − c)·d,
    /// t = −b' ∓ √(b'² − (|o − c|² − r²)) (the discriminant written as r² − |(o − c) − b'·d|²,
    /// which does not cancel for distant spheres; Haines et al., *Ray Tracing Gems* ch. 7).
    #[inline]
    #[must_use]
    pub fn intersect(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, Vec3)> {
        let oc = origin - self.center;
        let b = oc.dot(dir);
        let perp = oc - b * dir;
        let disc = self.radius * self.radius - perp.length_squared();
        if !(disc >= 0.0) {
            return None;
        }
        let root = disc.sqrt();
        let c = oc.length_squared() - self.radius * self.radius;
        // q = −b − sign(b)·√disc; the two roots are q and c/q.
        let q = -b - root.copysign(b);
        let (mut t0, mut t1) = (q, if q != 0.0 { c / q } else { -b });
        if t0 > t1 {
            core::mem::swap(&mut t0, &mut t1);
        }
        let t = if t0 > t_min { t0 } else { t1 };
        if !(t > t_min && t < t_max) {
            return None;
        }
        Some((t, (origin + t * dir - self.center) / self.radius))
    }
}

/// The geometry of a scene object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// An axis-aligned box.
    Box(Aabb),
    /// A sphere.
    Sphere(Sphere),
}

impl Shape {
    /// The first intersection of the ray with the shape for `t_min < t < t_max`: distance and
    /// outward normal.
    #[inline]
    #[must_use]
    pub fn intersect(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, Vec3)> {
        match self {
            Shape::Box(b) => b.intersect(origin, dir, t_min, t_max),
            Shape::Sphere(s) => s.intersect(origin, dir, t_min, t_max),
        }
    }

    /// Whether `p` lies inside the shape (or on its surface).
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        match self {
            Shape::Box(b) => b.contains(p),
            Shape::Sphere(s) => (p - s.center).length_squared() <= s.radius * s.radius,
        }
    }
}

/// An opaque, diffuse scene object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Object {
    /// Its geometry.
    pub shape: Shape,
    /// Diffuse reflectance ρ per channel, in [0, 1].
    pub albedo: Vec3,
}

/// A one-sided rectangular area light `corner + s·edge_u + t·edge_v`, s, t ∈ [0, 1], of
/// constant radiance, emitting on the side of `edge_u × edge_v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RectLight {
    /// One corner.
    pub corner: Vec3,
    /// First edge from the corner.
    pub edge_u: Vec3,
    /// Second edge from the corner (not parallel to `edge_u`).
    pub edge_v: Vec3,
    /// Emitted radiance L_e (linear RGB); zero for a light that is off.
    pub radiance: Vec3,
}

/// A point sampled on the light ([`RectLight::sample`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// The point on the light.
    pub point: Vec3,
    /// The light's unit normal (the side it emits to).
    pub normal: Vec3,
    /// The density of the point with respect to area, 1/A.
    pub pdf_area: f32,
}

impl RectLight {
    /// The unit normal, `normalize(edge_u × edge_v)`: the light emits into this half-space.
    #[inline]
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        self.edge_u.cross(self.edge_v).normalize()
    }

    /// The area |edge_u × edge_v|.
    #[inline]
    #[must_use]
    pub fn area(&self) -> f32 {
        self.edge_u.cross(self.edge_v).length()
    }

    /// The centre of the rectangle.
    #[inline]
    #[must_use]
    pub fn center(&self) -> Vec3 {
        self.corner + 0.5 * (self.edge_u + self.edge_v)
    }

    /// The point at the caller's uniforms `u` ∈ [0, 1)², uniformly distributed over the area
    /// (density 1/A).
    #[inline]
    #[must_use]
    pub fn sample(&self, u: Vec2) -> LightSample {
        LightSample {
            point: self.corner + u.x * self.edge_u + u.y * self.edge_v,
            normal: self.normal(),
            pdf_area: 1.0 / self.area(),
        }
    }

    /// Where the ray `origin + t·dir` hits the rectangle (either side) for `t_min < t < t_max`.
    #[inline]
    #[must_use]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        let n = self.edge_u.cross(self.edge_v);
        let denom = n.dot(dir);
        if denom == 0.0 {
            return None;
        }
        let t = n.dot(self.corner - origin) / denom;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let d = origin + t * dir - self.corner;
        // Coordinates in the (possibly non-orthogonal) edge basis via the dual basis.
        let uu = self.edge_u.dot(self.edge_u);
        let uv = self.edge_u.dot(self.edge_v);
        let vv = self.edge_v.dot(self.edge_v);
        let du = d.dot(self.edge_u);
        let dv = d.dot(self.edge_v);
        let det = uu * vv - uv * uv;
        let s = (du * vv - dv * uv) / det;
        let r = (dv * uu - du * uv) / det;
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r)).then_some(t)
    }
}

/// The closest surface a ray hits ([`Scene::intersect`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub distance: f32,
    /// The hit point.
    pub point: Vec3,
    /// Outward unit normal of the surface at the hit.
    pub normal: Vec3,
    /// What was hit.
    pub surface: Surface,
}

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surface {
    /// The object with this index in [`Scene::objects`], with its albedo.
    Object {
        /// Index into [`Scene::objects`].
        index: usize,
        /// The object's albedo.
        albedo: Vec3,
    },
    /// The area light.
    Light,
}

/// What a probe ray returns: its hit distance (for the visibility texels) and the radiance
/// arriving along it (for the irradiance texels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeRay {
    /// Distance to the first hit, or [`MISS_DISTANCE`].
    pub distance: f32,
    /// Radiance arriving at the ray origin from the ray direction (one bounce, see the
    /// [module docs](self)).
    pub radiance: Vec3,
    /// The ray hit the back of a surface (it started inside geometry).
    pub backface: bool,
}

/// One static moment of a scene: opaque diffuse objects and one rectangular area light.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The objects.
    pub objects: Vec<Object>,
    /// The light (set its radiance to zero to switch it off).
    pub light: RectLight,
}

impl Scene {
    /// The closest hit of the ray `origin + t·dir` (`dir` of unit length) with `t_min < t < t_max`,
    /// over all objects and the light.
    #[must_use]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        let mut best: Option<(f32, Vec3, Surface)> = None;
        let mut t_far = t_max;
        for (index, object) in self.objects.iter().enumerate() {
            if let Some((t, normal)) = object.shape.intersect(origin, dir, t_min, t_far) {
                t_far = t;
                best = Some((
                    t,
                    normal,
                    Surface::Object {
                        index,
                        albedo: object.albedo,
                    },
                ));
            }
        }
        if let Some(t) = self.light.intersect(origin, dir, t_min, t_far) {
            best = Some((t, self.light.normal(), Surface::Light));
        }
        best.map(|(distance, normal, surface)| Hit {
            distance,
            point: origin + distance * dir,
            normal,
            surface,
        })
    }

    /// Whether any object blocks the segment from `from` to `to` (the light itself does not
    /// block; the ends are excluded by [`RAY_EPSILON`]).
    #[must_use]
    pub fn occluded(&self, from: Vec3, to: Vec3) -> bool {
        let d = to - from;
        let len = d.length();
        if !(len > 2.0 * RAY_EPSILON) {
            return false;
        }
        let dir = d / len;
        let t_max = len - RAY_EPSILON;
        self.objects
            .iter()
            .any(|o| o.shape.intersect(from, dir, RAY_EPSILON, t_max).is_some())
    }

    /// Whether `p` lies inside an object (a probe there is useless; DDGI deactivates it).
    #[must_use]
    pub fn inside_geometry(&self, p: Vec3) -> bool {
        self.objects.iter().any(|o| o.shape.contains(p))
    }

    /// A one-sample estimate of the direct irradiance E_d at `point` with unit `normal`, from
    /// the light point at the caller's uniforms `u` ∈ [0, 1)²:
    ///
    /// E_d ≈ L_e · max(0, n·ω) · max(0, −n_l·ω) / d² / p_A,  ω = (y − x)/d, p_A = 1/A,
    ///
    /// times the visibility of the shadow ray from `point` to the light point y. Unbiased for
    /// E_d = ∫_A L_e V(x, y) cos θ_x cos θ_y / d² dA (area form of the rendering equation,
    /// Kajiya 1986; Pharr et al., *PBRT* 4th ed., sec. 4.2).
    #[must_use]
    pub fn direct_irradiance(&self, point: Vec3, normal: Vec3, u: Vec2) -> Vec3 {
        if self.light.radiance == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let s = self.light.sample(u);
        let d = s.point - point;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0) {
            return Vec3::ZERO;
        }
        let w = d / dist2.sqrt();
        let cos_x = normal.dot(w);
        let cos_y = -s.normal.dot(w);
        if !(cos_x > 0.0 && cos_y > 0.0) {
            return Vec3::ZERO;
        }
        let from = point + RAY_EPSILON * normal;
        if self.occluded(from, s.point) {
            return Vec3::ZERO;
        }
        self.light.radiance * (cos_x * cos_y / (dist2 * s.pdf_area))
    }

    /// Traces a probe ray from `origin` along unit `dir` and returns its hit distance and the
    /// one-bounce radiance it carries (see the [module docs](self)); `u` ∈ [0, 1)² are the
    /// uniforms of the light sample at the hit.
    #[must_use]
    pub fn trace_probe_ray(&self, origin: Vec3, dir: Vec3, u: Vec2) -> ProbeRay {
        let Some(hit) = self.intersect(origin, dir, 0.0, MISS_DISTANCE) else {
            return ProbeRay {
                distance: MISS_DISTANCE,
                radiance: Vec3::ZERO,
                backface: false,
            };
        };
        let backface = hit.normal.dot(dir) > 0.0;
        let radiance = match hit.surface {
            Surface::Light if !backface => self.light.radiance,
            Surface::Light => Vec3::ZERO,
            Surface::Object { albedo, .. } if !backface => {
                albedo
                    * core::f32::consts::FRAC_1_PI
                    * self.direct_irradiance(hit.point, hit.normal, u)
            }
            Surface::Object { .. } => Vec3::ZERO,
        };
        ProbeRay {
            distance: hit.distance,
            radiance,
            backface,
        }
    }
}

/// The kind of change a [`DynamicScene`] goes through at its event frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneEvent {
    /// The door in the partition wall slides open.
    DoorOpens,
    /// The light, off until then, switches on.
    LightSwitchesOn,
}

/// A scene that changes once: [`DynamicScene::before`] until `event_frame`, then a linear
/// transition over `transition_frames` frames to [`DynamicScene::after`] (the door slides, the
/// light dims up). `before` and `after` hold the same objects in the same order; only box
/// bounds, sphere centres and radii, and the light's radiance may differ.
#[derive(Clone, Debug, PartialEq)]
pub struct DynamicScene {
    /// The scene for frames `< event_frame`.
    pub before: Scene,
    /// The scene for frames `≥ event_frame + transition_frames − 1`.
    pub after: Scene,
    /// The first frame that differs from `before`.
    pub event_frame: u32,
    /// Frames the change takes (at least 1: 1 is an instant switch at `event_frame`). A
    /// gradual change is what ADGI's temporal gradients see (sec. 4.4 compares two frames that
    /// trace identical rays; a switch between two such frames would go unseen).
    pub transition_frames: u32,
    /// What changes.
    pub event: SceneEvent,
    /// Where the change happens (the doorway's centre, or the light's); error measurements
    /// "near the event" use probes around this point.
    pub event_center: Vec3,
    /// The region the event changes most: the closet behind the partition wall.
    pub event_region: Aabb,
    /// A probe grid that fits the rooms: no probe inside geometry.
    pub grid: ProbeGrid,
}

/// Dimensions of the two-room scene.
mod room {
    use glam::Vec3;
    /// Outer extent of the interior: x ∈ [0, 9], y ∈ [0, 3], z ∈ [0, 4].
    pub const SIZE: Vec3 = Vec3::new(9.0, 3.0, 4.0);
    /// The partition wall between the rooms spans x ∈ [8.0, 8.1].
    pub const WALL_X: (f32, f32) = (8.0, 8.1);
    /// The doorway: z ∈ [1.5, 2.5], y ∈ [0, 2.2].
    pub const DOOR_Z: (f32, f32) = (1.5, 2.5);
    /// Height of the doorway.
    pub const DOOR_H: f32 = 2.2;
    /// Wall thickness of the outer walls.
    pub const T: f32 = 0.1;
}

impl DynamicScene {
    /// The two-room scene (see the [module docs](self)) whose door starts sliding open at
    /// `event_frame` and is fully open `transition_frames − 1` frames later.
    #[must_use]
    pub fn door_opens(event_frame: u32, transition_frames: u32) -> Self {
        Self::two_rooms(SceneEvent::DoorOpens, event_frame, transition_frames)
    }

    /// The two-room scene with the door open and the light dimming up from off at
    /// `event_frame` over `transition_frames` frames.
    #[must_use]
    pub fn light_switches_on(event_frame: u32, transition_frames: u32) -> Self {
        Self::two_rooms(SceneEvent::LightSwitchesOn, event_frame, transition_frames)
    }

    fn two_rooms(event: SceneEvent, event_frame: u32, transition_frames: u32) -> Self {
        let closed = Aabb::new(
            Vec3::new(room::WALL_X.0, 0.0, room::DOOR_Z.0),
            Vec3::new(room::WALL_X.1, room::DOOR_H, room::DOOR_Z.1),
        );
        // Slid along the wall (on the closet's face) past the doorway's far edge.
        let open = Aabb::new(
            Vec3::new(room::WALL_X.1, 0.0, room::DOOR_Z.1 + 0.05),
            Vec3::new(room::WALL_X.1 + 0.05, room::DOOR_H, room::DOOR_Z.1 + 1.05),
        );
        let make = |door: Aabb, light_on: bool| {
            let mut scene = Self::rooms_without_door(light_on);
            scene.objects.push(Object {
                shape: Shape::Box(door),
                albedo: Vec3::new(0.55, 0.4, 0.25),
            });
            scene
        };
        let (before, after) = match event {
            SceneEvent::DoorOpens => (make(closed, true), make(open, true)),
            SceneEvent::LightSwitchesOn => (make(open, false), make(open, true)),
        };
        let event_center = match event {
            SceneEvent::DoorOpens => closed.center(),
            SceneEvent::LightSwitchesOn => after.light.center(),
        };
        let grid = ProbeGrid::new(
            Vec3::new(0.25, 0.375, 0.25),
            Vec3::new(0.5, 0.75, 0.5),
            UVec3::new(18, 4, 8),
        )
        .expect("valid constant grid");
        Self {
            before,
            after,
            event_frame,
            transition_frames: transition_frames.max(1),
            event,
            event_center,
            event_region: Aabb::new(
                Vec3::new(room::WALL_X.1, 0.0, 0.0),
                Vec3::new(room::SIZE.x, room::SIZE.y, room::SIZE.z),
            ),
            grid,
        }
    }

    /// The walls, floor, ceiling, partition (with its doorway open), a sphere, and the light.
    fn rooms_without_door(light_on: bool) -> Scene {
        let s = room::SIZE;
        let t = room::T;
        let white = Vec3::splat(0.7);
        let b = |min: Vec3, max: Vec3, albedo: Vec3| Object {
            shape: Shape::Box(Aabb::new(min, max)),
            albedo,
        };
        let (wx0, wx1) = room::WALL_X;
        let (dz0, dz1) = room::DOOR_Z;
        let objects = std::vec![
            // Floor and ceiling.
            b(
                Vec3::new(-t, -t, -t),
                Vec3::new(s.x + t, 0.0, s.z + t),
                white
            ),
            b(
                Vec3::new(-t, s.y, -t),
                Vec3::new(s.x + t, s.y + t, s.z + t),
                white
            ),
            // Red wall at x = 0, green wall at x = 9, white walls at z = 0 and z = 4.
            b(
                Vec3::new(-t, 0.0, 0.0),
                Vec3::new(0.0, s.y, s.z),
                Vec3::new(0.65, 0.1, 0.08)
            ),
            b(
                Vec3::new(s.x, 0.0, 0.0),
                Vec3::new(s.x + t, s.y, s.z),
                Vec3::new(0.1, 0.6, 0.12)
            ),
            b(Vec3::new(0.0, 0.0, -t), Vec3::new(s.x, s.y, 0.0), white),
            b(
                Vec3::new(0.0, 0.0, s.z),
                Vec3::new(s.x, s.y, s.z + t),
                white
            ),
            // Partition wall with a doorway.
            b(Vec3::new(wx0, 0.0, 0.0), Vec3::new(wx1, s.y, dz0), white),
            b(Vec3::new(wx0, 0.0, dz1), Vec3::new(wx1, s.y, s.z), white),
            b(
                Vec3::new(wx0, room::DOOR_H, dz0),
                Vec3::new(wx1, s.y, dz1),
                white
            ),
            // A sphere between the probes of the main room, resting on the floor.
            Object {
                shape: Shape::Sphere(Sphere {
                    center: Vec3::new(1.5, 0.3, 1.0),
                    radius: 0.3,
                }),
                albedo: Vec3::new(0.75, 0.7, 0.3),
            },
        ];
        let light = RectLight {
            corner: Vec3::new(5.4, s.y - 0.01, 1.4),
            edge_u: Vec3::new(1.2, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 1.2),
            radiance: if light_on {
                Vec3::new(5.0, 4.6, 3.8)
            } else {
                Vec3::ZERO
            },
        };
        Scene { objects, light }
    }

    /// How far the change has gone at frame `frame`: 0 before `event_frame`, then
    /// `(frame − event_frame + 1) / transition_frames`, clamped to 1.
    #[inline]
    #[must_use]
    pub fn progress(&self, frame: u32) -> f32 {
        if frame < self.event_frame {
            return 0.0;
        }
        let k = (frame - self.event_frame + 1) as f32 / self.transition_frames.max(1) as f32;
        k.min(1.0)
    }

    /// The scene at frame `frame`: `before` and `after` blended by [`Self::progress`] (box
    /// bounds, spheres and light radiance interpolated linearly).
    #[must_use]
    pub fn at_frame(&self, frame: u32) -> Scene {
        let s = self.progress(frame);
        if s <= 0.0 {
            return self.before.clone();
        }
        if s >= 1.0 {
            return self.after.clone();
        }
        let objects = self
            .before
            .objects
            .iter()
            .zip(&self.after.objects)
            .map(|(a, b)| {
                let shape = match (a.shape, b.shape) {
                    (Shape::Box(x), Shape::Box(y)) => {
                        Shape::Box(Aabb::new(x.min.lerp(y.min, s), x.max.lerp(y.max, s)))
                    }
                    (Shape::Sphere(x), Shape::Sphere(y)) => Shape::Sphere(Sphere {
                        center: x.center.lerp(y.center, s),
                        radius: x.radius + s * (y.radius - x.radius),
                    }),
                    (_, other) => other,
                };
                Object {
                    shape,
                    albedo: b.albedo,
                }
            })
            .collect();
        let mut light = self.after.light;
        light.radiance = self
            .before
            .light
            .radiance
            .lerp(self.after.light.radiance, s);
        Scene { objects, light }
    }

    /// Indices of the probes of [`DynamicScene::grid`] near the event: inside
    /// [`DynamicScene::event_region`] or within `radius` of [`DynamicScene::event_center`].
    #[must_use]
    pub fn probes_near_event(&self, radius: f32) -> Vec<usize> {
        (0..self.grid.probe_count())
            .filter(|&i| {
                let p = self.grid.probe_position(self.grid.probe_coords(i));
                self.event_region.contains(p) || p.distance(self.event_center) <= radius
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32, tol: f32) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn box_hits_by_hand() {
        let b = Aabb::new(Vec3::new(1.0, -1.0, -1.0), Vec3::new(3.0, 1.0, 1.0));
        // Straight along +x from the origin: enters the face x = 1.
        let (t, n) = b.intersect(Vec3::ZERO, Vec3::X, 0.0, 100.0).unwrap();
        assert_eq!((t, n), (1.0, -Vec3::X));
        // From inside: leaves through x = 3 (a back face, normal +x along the ray).
        let (t, n) = b
            .intersect(Vec3::new(2.0, 0.0, 0.0), Vec3::X, 0.0, 100.0)
            .unwrap();
        assert_eq!((t, n), (1.0, Vec3::X));
        // Diagonal in the xy-plane from (0, −2, 0): enters y = −1 at t·(1/√2) = 1, x = 1.
        let d = Vec3::new(1.0, 1.0, 0.0).normalize();
        let (t, n) = b
            .intersect(Vec3::new(0.0, -2.0, 0.0), d, 0.0, 100.0)
            .unwrap();
        assert!(close(t, 2.0_f32.sqrt(), 1e-6), "{t}");
        assert!(n == -Vec3::Y || n == -Vec3::X);
        // Misses, hits behind the origin, and t_max.
        assert!(b.intersect(Vec3::ZERO, Vec3::Y, 0.0, 100.0).is_none());
        assert!(b.intersect(Vec3::ZERO, -Vec3::X, 0.0, 100.0).is_none());
        assert!(b.intersect(Vec3::ZERO, Vec3::X, 0.0, 0.5).is_none());
        // Entering the y-face: from (2, −3, 0) up.
        let (t, n) = b
            .intersect(Vec3::new(2.0, -3.0, 0.0), Vec3::Y, 0.0, 100.0)
            .unwrap();
        assert_eq!((t, n), (2.0, -Vec3::Y));
    }

    #[test]
    fn sphere_hits_by_hand() {
        let s = Sphere {
            center: Vec3::new(0.0, 0.0, 5.0),
            radius: 2.0,
        };
        let (t, n) = s.intersect(Vec3::ZERO, Vec3::Z, 0.0, 100.0).unwrap();
        assert!(close(t, 3.0, 1e-6));
        assert!((n + Vec3::Z).length() < 1e-6);
        // From the centre: the far side at t = 2.
        let (t, n) = s
            .intersect(Vec3::new(0.0, 0.0, 5.0), Vec3::X, 0.0, 100.0)
            .unwrap();
        assert!(close(t, 2.0, 1e-6));
        assert!((n - Vec3::X).length() < 1e-6);
        // Grazing offset ray x = 1: t = 5 − √3.
        let (t, _) = s
            .intersect(Vec3::new(1.0, 0.0, 0.0), Vec3::Z, 0.0, 100.0)
            .unwrap();
        assert!(close(t, 5.0 - 3.0_f32.sqrt(), 1e-5), "{t}");
        assert!(
            s.intersect(Vec3::new(2.5, 0.0, 0.0), Vec3::Z, 0.0, 100.0)
                .is_none()
        );
        assert!(s.intersect(Vec3::ZERO, -Vec3::Z, 0.0, 100.0).is_none());
        assert!(s.intersect(Vec3::ZERO, Vec3::Z, 0.0, 2.9).is_none());
        // A distant sphere keeps its precision (the stable discriminant).
        let far = Sphere {
            center: Vec3::new(0.0, 0.0, 1.0e4),
            radius: 1.0,
        };
        let (t, _) = far.intersect(Vec3::ZERO, Vec3::Z, 0.0, 1.0e5).unwrap();
        assert!(close(t, 1.0e4 - 1.0, 1e-2), "{t}");
    }

    #[test]
    fn light_hits_and_sampling_density() {
        let light = RectLight {
            corner: Vec3::new(-1.0, 2.0, -0.5),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 1.0),
            radiance: Vec3::ONE,
        };
        assert!((light.normal() + Vec3::Y).length() < 1e-6, "emits down");
        assert!(close(light.area(), 2.0, 1e-6));
        assert_eq!(light.intersect(Vec3::ZERO, Vec3::Y, 0.0, 10.0), Some(2.0));
        assert!(
            light
                .intersect(Vec3::new(1.5, 0.0, 0.0), Vec3::Y, 0.0, 10.0)
                .is_none()
        );
        // Samples cover the rectangle uniformly: pdf 1/A, the mean is the centre, and a grid of
        // uniforms maps to a grid of points.
        let n = 16;
        let mut mean = Vec3::ZERO;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let s = light.sample(u);
                assert_eq!(s.pdf_area, 0.5);
                assert!(
                    light
                        .intersect(Vec3::new(s.point.x, 0.0, s.point.z), Vec3::Y, 0.0, 10.0)
                        .is_some()
                );
                mean += s.point;
            }
        }
        mean /= (n * n) as f32;
        assert!((mean - light.center()).length() < 1e-5);
    }

    /// The direct irradiance estimator, averaged over a fine grid of uniforms, matches the
    /// closed form for an unoccluded polygonal light: Lambert's formula
    /// E = L/2 · |Σ_edges Θ_i (n · Γ_i)| (Arvo 1995, *Applications of irradiance tensors*).
    #[test]
    fn direct_irradiance_matches_lambert_formula() {
        let light = RectLight {
            corner: Vec3::new(-0.5, 1.0, -0.5),
            edge_u: Vec3::new(1.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 1.0),
            radiance: Vec3::splat(3.0),
        };
        let scene = Scene {
            objects: Vec::new(),
            light,
        };
        let x = Vec3::new(0.2, 0.0, -0.1);
        let n = Vec3::Y;
        // Lambert's polygon formula (Arvo 1995): E = L/2 · Σ Θ_i (n · Γ_i).
        let verts = [
            light.corner,
            light.corner + light.edge_u,
            light.corner + light.edge_u + light.edge_v,
            light.corner + light.edge_v,
        ];
        let mut sum = 0.0_f64;
        for i in 0..4 {
            let a = (verts[i] - x).normalize();
            let b = (verts[(i + 1) % 4] - x).normalize();
            let theta = a.dot(b).clamp(-1.0, 1.0).acos();
            let g = a.cross(b).normalize();
            sum += f64::from(theta * g.dot(n));
        }
        let exact = 3.0 * 0.5 * sum.abs();
        let k = 64;
        let mut est = 0.0_f64;
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                est += scene.direct_irradiance(x, n, u).x as f64;
            }
        }
        est /= (k * k) as f64;
        mcg_test_support::assert_close!(est / exact, 1.0, 2e-3, "{est} vs {exact}");
        // Facing away, or the light off: nothing.
        assert_eq!(scene.direct_irradiance(x, -n, Vec2::splat(0.5)), Vec3::ZERO);
    }

    #[test]
    fn shadow_rays_and_probe_rays() {
        let scene = DynamicScene::door_opens(10, 4);
        let closed = &scene.before;
        let open = &scene.after;
        // A floor point in the closet behind the doorway is in shadow with the door closed,
        // and lit by the light's centre with it open.
        let p = Vec3::new(8.6, 0.0, 2.0);
        let u = Vec2::splat(0.5);
        assert_eq!(closed.direct_irradiance(p, Vec3::Y, u), Vec3::ZERO);
        assert!(open.direct_irradiance(p, Vec3::Y, u).x > 0.0);
        // Straight up from under the light: the probe ray sees L_e at the light's distance.
        let r = open.trace_probe_ray(Vec3::new(6.0, 1.0, 2.0), Vec3::Y, u);
        assert!(close(r.distance, 1.99, 1e-5));
        assert_eq!(r.radiance, open.light.radiance);
        assert!(!r.backface);
        // Down onto the floor: ρ/π · E_d.
        let r = open.trace_probe_ray(Vec3::new(6.0, 1.0, 2.0), -Vec3::Y, u);
        assert!(close(r.distance, 1.0, 1e-6));
        let e = open.direct_irradiance(Vec3::new(6.0, 0.0, 2.0), Vec3::Y, u);
        assert!((r.radiance - 0.7 * e / core::f32::consts::PI).length() < 1e-5);
        // From inside the sphere: a back face, no radiance.
        let r = open.trace_probe_ray(Vec3::new(1.5, 0.3, 1.0), Vec3::X, u);
        assert!(r.backface && r.radiance == Vec3::ZERO);
        assert!(close(r.distance, 0.3, 1e-6));
        // The door slides over frames 10..=13.
        assert_eq!(scene.at_frame(9), scene.before);
        assert_eq!(scene.at_frame(13), scene.after);
        assert_eq!(scene.at_frame(99), scene.after);
        let mid = scene.at_frame(11);
        let door = |s: &Scene| match s.objects.last().unwrap().shape {
            Shape::Box(b) => b,
            Shape::Sphere(_) => unreachable!(),
        };
        let (a, b, m) = (door(&scene.before), door(&scene.after), door(&mid));
        assert!((m.min - a.min.lerp(b.min, 0.5)).length() < 1e-6);
        let lit = DynamicScene::light_switches_on(0, 2);
        assert_eq!(
            lit.at_frame(0).light.radiance,
            0.5 * lit.after.light.radiance
        );
    }

    #[test]
    fn default_grid_fits_the_rooms() {
        for scene in [
            DynamicScene::door_opens(0, 1),
            DynamicScene::light_switches_on(0, 1),
        ] {
            let g = scene.grid;
            for i in 0..g.probe_count() {
                let p = g.probe_position(g.probe_coords(i));
                for s in [&scene.before, &scene.after] {
                    assert!(!s.inside_geometry(p), "probe {i} at {p} inside geometry");
                    // No probe closer than 0.05 to a surface (a ray in each axis direction).
                    for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
                        let h = s.intersect(p, d, 0.0, MISS_DISTANCE).expect("closed room");
                        assert!(h.distance > 0.05, "probe {i} at {p} too close along {d}");
                    }
                }
            }
            let near = scene.probes_near_event(1.0);
            assert!(
                near.len() > 20 && near.len() < g.probe_count() / 2,
                "{}",
                near.len()
            );
        }
    }

    #[test]
    fn value_stability() {
        let scene = DynamicScene::door_opens(0, 1);
        let r = scene.after.trace_probe_ray(
            Vec3::new(8.75, 0.375, 2.25),
            Vec3::new(-0.6, 0.8, 0.0),
            Vec2::new(0.3, 0.7),
        );
        // Through the doorway onto the unlit ceiling (the light faces down): no radiance.
        assert_eq!(r.distance.to_bits(), 1_079_115_776);
        assert_eq!(r.radiance.to_array().map(f32::to_bits), [0; 3]);
        // Through the doorway onto the lit floor of the main room.
        let r = scene.after.trace_probe_ray(
            Vec3::new(8.75, 0.375, 2.25),
            Vec3::new(-0.9, -0.3, 0.1).normalize(),
            Vec2::new(0.3, 0.7),
        );
        assert_eq!(r.distance.to_bits(), 1_066_967_384);
        assert_eq!(
            r.radiance.to_array().map(f32::to_bits),
            [1_035_856_274, 1_034_860_587, 1_032_869_210]
        );
    }
}
