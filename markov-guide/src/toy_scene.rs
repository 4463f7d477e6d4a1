//! A toy light field with closed-form direct illumination, for tests, benchmarks and examples.
//!
//! Shading points lie on the plane z = 0 with normal +z; the scene holds small spherical
//! emitters of constant radiance (which may move at constant velocity, appear and vanish) and
//! opaque black spherical occluders. Everything else is black. The incident-light integrand
//! at a point x is f(ω) = L(x, ω)·max(0, n·ω) and its integral is the irradiance
//! E(x) = Σ_lights π L (r/d)² cos θ_c for every light that lies entirely above the horizon and
//! is not occluded (the exact irradiance from a sphere, e.g. Snyder 1996, *Area light sources
//! for real-time graphics*).

use std::vec::Vec;

use glam::Vec3;

/// Rays that hit nothing end this far away.
pub const MISS_DISTANCE: f32 = 1.0e4;

/// A spherical emitter of constant radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereLight {
    /// Centre at time 0.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
    /// Emitted radiance (luminance), the same in every direction.
    pub radiance: f32,
    /// Velocity: the centre at time t is `center + t·velocity`.
    pub velocity: Vec3,
    /// The light exists for `appear ≤ t < vanish`.
    pub appear: f32,
    /// See [`SphereLight::appear`].
    pub vanish: f32,
}

impl SphereLight {
    /// A static light that always exists.
    #[must_use]
    pub const fn fixed(center: Vec3, radius: f32, radiance: f32) -> Self {
        Self {
            center,
            radius,
            radiance,
            velocity: Vec3::ZERO,
            appear: f32::NEG_INFINITY,
            vanish: f32::INFINITY,
        }
    }
}

/// An opaque, black sphere that blocks light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Occluder {
    /// Centre.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
}

/// What a ray from a shading point finds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToyHit {
    /// The hit point (on a light or occluder), or the point [`MISS_DISTANCE`] along the ray.
    pub point: Vec3,
    /// Radiance arriving along the ray (0 unless a light was hit).
    pub radiance: f32,
    /// Index of the light that was hit.
    pub light: Option<usize>,
    /// Velocity of the object that was hit (a moving light's), zero otherwise: the hit point
    /// was at `point − velocity·dt` a time dt earlier.
    pub velocity: Vec3,
}

/// The toy scene at one moment: lights and occluders above the plane z = 0.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ToyScene {
    /// The emitters.
    pub lights: Vec<SphereLight>,
    /// The occluders.
    pub occluders: Vec<Occluder>,
}

/// Normal of every shading point of the toy scene.
pub const TOY_NORMAL: Vec3 = Vec3::Z;

impl ToyScene {
    /// One light of radius 0.25 at height 3 above the origin, radiance 40.
    #[must_use]
    pub fn single_light() -> Self {
        Self {
            lights: std::vec![SphereLight::fixed(Vec3::new(0.0, 0.0, 3.0), 0.25, 40.0)],
            occluders: Vec::new(),
        }
    }

    /// One large light, radius 1.5 at height 3.5 above the origin (about 25° across), radiance
    /// 10: the broad emitter of a Cornell box, where a lobe follows its own samples most.
    #[must_use]
    pub fn large_light() -> Self {
        Self {
            lights: std::vec![SphereLight::fixed(Vec3::new(0.0, 0.0, 3.5), 1.5, 10.0)],
            occluders: Vec::new(),
        }
    }

    /// Eight lights of radius 0.15 on a ring of radius 3 at heights 1.5 to 3.25, radiances
    /// 20 to 90, so that they differ in direction, distance and power.
    #[must_use]
    pub fn eight_lights() -> Self {
        let lights = (0..8)
            .map(|i| {
                let angle = i as f32 * core::f32::consts::TAU / 8.0;
                let height = 1.5 + 0.25 * i as f32;
                let center = Vec3::new(3.0 * angle.cos(), 3.0 * angle.sin(), height);
                SphereLight::fixed(center, 0.15, 20.0 + 10.0 * i as f32)
            })
            .collect();
        Self {
            lights,
            occluders: Vec::new(),
        }
    }

    /// One light of radius 0.2 and radiance 60 that starts at (−2, 0, 2.5) and moves along +x
    /// at `speed` units per time unit.
    #[must_use]
    pub fn moving_light(speed: f32) -> Self {
        let mut light = SphereLight::fixed(Vec3::new(-2.0, 0.0, 2.5), 0.2, 60.0);
        light.velocity = Vec3::new(speed, 0.0, 0.0);
        Self {
            lights: std::vec![light],
            occluders: Vec::new(),
        }
    }

    /// The scene at time `t`: lights moved by their velocity, those outside their lifetime removed.
    #[must_use]
    pub fn at_time(&self, t: f32) -> Self {
        let lights = self
            .lights
            .iter()
            .filter(|l| l.appear <= t && t < l.vanish)
            .map(|l| SphereLight {
                center: l.center + t * l.velocity,
                ..*l
            })
            .collect();
        Self {
            lights,
            occluders: self.occluders.clone(),
        }
    }

    /// Traces a ray from `x` in unit direction `w` and returns the nearest hit.
    #[must_use]
    pub fn trace(&self, x: Vec3, w: Vec3) -> ToyHit {
        let mut nearest = ToyHit {
            point: x + MISS_DISTANCE * w,
            radiance: 0.0,
            light: None,
            velocity: Vec3::ZERO,
        };
        let mut t_max = MISS_DISTANCE;
        for (i, light) in self.lights.iter().enumerate() {
            if let Some(t) = ray_sphere(x, w, light.center, light.radius)
                && t < t_max
            {
                t_max = t;
                nearest = ToyHit {
                    point: x + t * w,
                    radiance: light.radiance,
                    light: Some(i),
                    velocity: light.velocity,
                };
            }
        }
        for occluder in &self.occluders {
            if let Some(t) = ray_sphere(x, w, occluder.center, occluder.radius)
                && t < t_max
            {
                t_max = t;
                nearest = ToyHit {
                    point: x + t * w,
                    radiance: 0.0,
                    light: None,
                    velocity: Vec3::ZERO,
                };
            }
        }
        nearest
    }

    /// The integrand of the irradiance at shading point `x` (on the plane, normal +z):
    /// L(x, ω)·max(0, n·ω).
    #[must_use]
    pub fn integrand(&self, x: Vec3, w: Vec3) -> f32 {
        let cos = TOY_NORMAL.dot(w);
        if cos <= 0.0 {
            return 0.0;
        }
        self.trace(x, w).radiance * cos
    }

    /// The exact irradiance E(x) = ∫ L(x, ω) max(0, n·ω) dω at shading point `x`, in f64.
    ///
    /// Exact for lights entirely above the horizon of `x`, each either fully visible or fully
    /// hidden behind one occluder. Returns `None` when a light dips below the horizon or is
    /// partly occluded (no closed form then).
    #[must_use]
    pub fn irradiance(&self, x: Vec3) -> Option<f64> {
        let x = F64Vec::from(x);
        let mut total = 0.0;
        for light in &self.lights {
            let to_light = F64Vec::from(light.center).sub(x);
            let d = to_light.length();
            let r = light.radius as f64;
            // The sphere lies above the tangent plane z = x.z iff its lowest point does.
            if to_light.0[2] <= r || d <= r {
                return None;
            }
            let sin_light = r / d;
            let light_half_angle = sin_light.asin();
            let mut hidden = false;
            for occluder in &self.occluders {
                let to_occ = F64Vec::from(occluder.center).sub(x);
                let d_occ = to_occ.length();
                let r_occ = occluder.radius as f64;
                if d_occ <= r_occ {
                    return None;
                }
                let occ_half_angle = (r_occ / d_occ).asin();
                let between = (to_light.dot(to_occ) / (d * d_occ)).clamp(-1.0, 1.0).acos();
                if between >= light_half_angle + occ_half_angle {
                    continue; // cones disjoint
                }
                // Fully hidden: the light's cone inside the occluder's, and the occluder in front.
                if between + light_half_angle <= occ_half_angle && d_occ + r_occ < d - r {
                    hidden = true;
                    continue;
                }
                return None;
            }
            if !hidden {
                let cos_center = to_light.0[2] / d;
                total += core::f64::consts::PI
                    * light.radiance as f64
                    * sin_light
                    * sin_light
                    * cos_center;
            }
        }
        Some(total)
    }
}

/// A 3-vector in f64 for the closed-form reference.
#[derive(Clone, Copy)]
struct F64Vec([f64; 3]);

impl From<Vec3> for F64Vec {
    fn from(v: Vec3) -> Self {
        Self([v.x as f64, v.y as f64, v.z as f64])
    }
}

impl F64Vec {
    fn sub(self, o: Self) -> Self {
        Self([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
    fn dot(self, o: Self) -> f64 {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    fn length(self) -> f64 {
        self.dot(self).sqrt()
    }
}

/// Distance along the ray to the first intersection with a sphere in front of the origin.
fn ray_sphere(origin: Vec3, w: Vec3, center: Vec3, radius: f32) -> Option<f32> {
    let oc = center - origin;
    let b = oc.dot(w);
    // |oc − b·w|² is the squared distance of the centre from the ray's line, computed without
    // the cancellation of |oc|² − b².
    let perp = oc - b * w;
    let disc = radius * radius - perp.length_squared();
    if disc < 0.0 {
        return None;
    }
    let h = disc.sqrt();
    let near = b - h;
    let far = b + h;
    if near > 1e-6 {
        Some(near)
    } else if far > 1e-6 {
        Some(far)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E(x) by brute-force quadrature of the integrand over the hemisphere (midpoint rule in
    /// (cos²θ, φ), which makes the cosine weight uniform).
    fn quadrature(scene: &ToyScene, x: Vec3, n: usize) -> f64 {
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let s = (i as f64 + 0.5) / n as f64; // sin²θ
                let phi = (j as f64 + 0.5) / n as f64 * core::f64::consts::TAU;
                let sin = s.sqrt();
                let cos = (1.0 - s).sqrt();
                let w = Vec3::new(
                    (sin * phi.cos()) as f32,
                    (sin * phi.sin()) as f32,
                    cos as f32,
                );
                // dω·cosθ = π · d(sin²θ) dφ / (2π): weight π/n² per cell.
                sum += scene.trace(x, w.normalize()).radiance as f64;
            }
        }
        sum * core::f64::consts::PI / (n * n) as f64
    }

    #[test]
    fn closed_form_matches_quadrature() {
        let mut scene = ToyScene::eight_lights();
        for l in &mut scene.lights {
            l.radius = 0.6; // large, so the quadrature resolves them
        }
        let x = Vec3::new(0.3, -0.2, 0.0);
        let exact = scene.irradiance(x).unwrap();
        let approx = quadrature(&scene, x, 1500);
        assert!(
            ((approx - exact) / exact).abs() < 0.01,
            "{approx} vs {exact}"
        );
    }

    #[test]
    fn occluded_light_contributes_nothing() {
        let mut scene = ToyScene::single_light();
        scene.occluders.push(Occluder {
            center: Vec3::new(0.0, 0.0, 1.0),
            radius: 0.3,
        });
        assert_eq!(scene.irradiance(Vec3::ZERO), Some(0.0));
        assert_eq!(scene.trace(Vec3::ZERO, Vec3::Z).radiance, 0.0);
        // Far to the side, the cones are disjoint: the light counts again.
        let e = scene.irradiance(Vec3::new(5.0, 0.0, 0.0)).unwrap();
        assert!(e > 0.0);
        // In between, the light is partly hidden: no closed form.
        assert_eq!(scene.irradiance(Vec3::new(0.5, 0.0, 0.0)), None);
    }

    #[test]
    fn lights_move_and_vanish() {
        let mut scene = ToyScene::moving_light(2.0);
        scene.lights[0].vanish = 1.0;
        assert_eq!(
            scene.at_time(0.5).lights[0].center,
            Vec3::new(-1.0, 0.0, 2.5)
        );
        assert!(scene.at_time(1.0).lights.is_empty());
        assert_eq!(scene.at_time(1.0).irradiance(Vec3::ZERO), Some(0.0));
    }

    #[test]
    fn hits_report_points_on_the_light() {
        let scene = ToyScene::single_light();
        let hit = scene.trace(Vec3::ZERO, Vec3::Z);
        assert_eq!(hit.light, Some(0));
        mcg_test_support::assert_close!(hit.point.z, 2.75, 1e-5);
        let miss = scene.trace(Vec3::ZERO, Vec3::X);
        assert_eq!(miss.light, None);
        assert_eq!(miss.radiance, 0.0);
    }
}
