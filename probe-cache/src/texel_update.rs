//! Updates of a probe's texels from traced rays: ADGI's per-sample update and DDGI's
//! cosine-weighted blend of a batch of rays. Both take `&self` and run from any number of
//! threads at once: every texel word changes by compare-and-swap only ([`ProbeTexels`]).

use glam::{Vec2, Vec3};
use mcg_color_codec::MovingAverage;

use crate::ProbeTexels;
use crate::probe_texels::rotate_uniform;

/// One traced ray from a probe: where it went, what it brought back, how far it got.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaySample {
    /// Direction the ray left the probe in (need not be unit length).
    pub direction: Vec3,
    /// Radiance arriving at the probe along the ray, linear RGB (NaN: a failed ray, ignored;
    /// +∞ saturates the codec).
    pub radiance: Vec3,
    /// Hit distance in world units (`f32::INFINITY` for a miss; NaN ignored).
    pub distance: f32,
}

/// Exponents of DDGI's cosine-weighted blend: a ray in direction ω contributes to the texel with
/// centre direction n with weight `max(0, n·ω)^power` (DDGI, Majercik et al. 2019, sec. 4;
/// the RTXGI SDK's `ProbeBlendingCS`: power 1 for irradiance, `probeDistanceExponent` = 50 for
/// distance, which makes the distance texels nearly a nearest-direction lookup).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendWeights {
    /// Exponent of the irradiance weight (DDGI: 1, the cosine of the Lambertian lobe).
    pub irradiance_power: f32,
    /// Exponent of the distance weight (RTXGI: 50).
    pub distance_power: f32,
}

impl BlendWeights {
    /// DDGI's / RTXGI's exponents: 1 and 50.
    pub const DDGI: BlendWeights = BlendWeights {
        irradiance_power: 1.0,
        distance_power: 50.0,
    };
}

impl Default for BlendWeights {
    fn default() -> Self {
        Self::DDGI
    }
}

/// Weight sums of DDGI's blend ([`ProbeTexels::blend_rays`]) at or below this are treated as
/// "no ray reached the texel" (RTXGI's epsilon); public so that a GPU twin reads the same value.
pub const BLEND_WEIGHT_EPSILON: f32 = 1e-9;

impl ProbeTexels {
    /// ADGI's per-sample update (Alg. 2 line 3, Alg. 4): the sample lands in the irradiance
    /// texel and the visibility texel of its direction at probe `probe`, and each word takes one
    /// moving-average step — toward the ray's radiance and toward `(t, t²)`, `t` its hit distance
    /// in cell diagonals ([`ProbeTexels::normalise_distance`]). `u` is the caller's uniform for
    /// stochastic rounding (the visibility word uses a rotation of it).
    ///
    /// The irradiance texels so filled hold mean *radiance* per texel: query them with
    /// [`crate::TexelContent::Radiance`]. ADGI traces the visibility ray separately (in −ω from
    /// the sample's origin, sec. 4.8); a caller doing so calls
    /// [`Self::update_radiance_sample`] and [`Self::update_distance_sample`] separately.
    #[inline]
    pub fn update_sample(&self, probe: usize, sample: &RaySample, u: f32) {
        self.update_sample_with(probe, sample, u, self.config().moving_average);
    }

    /// [`Self::update_sample`] with another N_max for this sample (ADGI's dynamic chain:
    /// [`MovingAverage::DYNAMIC`], Table 3), in both the irradiance and the visibility word.
    #[inline]
    pub fn update_sample_with(
        &self,
        probe: usize,
        sample: &RaySample,
        u: f32,
        average: MovingAverage,
    ) {
        let im = &self.config().irradiance_map;
        let texel = im.index(im.texel(sample.direction));
        self.update_irradiance_with(probe, texel, sample.radiance, u, average);
        if let Some(t) = self.normalise_distance(sample.distance) {
            let vm = &self.config().visibility_map;
            let texel = vm.index(vm.texel(sample.direction));
            let moments = Vec2::new(t, t * t);
            self.update_visibility_with(probe, texel, moments, rotate_uniform(u, 1), average);
        }
    }

    /// The probe nearest to `position` (each coordinate rounded to the nearest lattice point and
    /// clamped to the grid; NaN reads as the origin): where ADGI's Algorithm 2 stores a sample
    /// taken at a continuous position ("the closest entry in the probes").
    #[inline]
    #[must_use]
    pub fn nearest_probe(&self, position: Vec3) -> usize {
        let grid = self.grid();
        let t = ((position - grid.origin()) / grid.spacing()).round();
        let max = (grid.counts() - glam::UVec3::ONE).as_vec3();
        // `max` maps NaN to 0; `as` saturates.
        let c = t.max(Vec3::ZERO).min(max).as_uvec3();
        grid.probe_index(c)
    }

    /// [`Self::update_sample`] at the probe nearest to `position` ([`Self::nearest_probe`]),
    /// for samples whose position a Metropolis chain chose continuously (ADGI sec. 3, Alg. 2).
    #[inline]
    pub fn update_sample_at(&self, position: Vec3, sample: &RaySample, u: f32) {
        self.update_sample(self.nearest_probe(position), sample, u);
    }

    /// The irradiance half of [`Self::update_sample`]: one moving-average step of the
    /// irradiance texel that `direction` lands in toward `radiance`.
    #[inline]
    pub fn update_radiance_sample(&self, probe: usize, direction: Vec3, radiance: Vec3, u: f32) {
        let map = &self.config().irradiance_map;
        let texel = map.index(map.texel(direction));
        self.update_irradiance(probe, texel, radiance, u);
    }

    /// The visibility half of [`Self::update_sample`]: one moving-average step of the
    /// visibility texel that `direction` lands in toward `(t, t²)`, `t = distance / diagonal`
    /// clamped to [`Self::max_distance`]. A NaN distance changes nothing.
    #[inline]
    pub fn update_distance_sample(&self, probe: usize, direction: Vec3, distance: f32, u: f32) {
        let Some(t) = self.normalise_distance(distance) else {
            return;
        };
        let map = &self.config().visibility_map;
        let texel = map.index(map.texel(direction));
        self.update_visibility(probe, texel, Vec2::new(t, t * t), u);
    }

    /// DDGI's blend of one probe's batch of rays into all its texels: every interior texel with
    /// centre direction n takes the weighted mean
    ///
    /// ```text
    /// x̄_n = Σ_r w_r x_r / Σ_r w_r,   w_r = max(0, n·ω_r)^power
    /// ```
    ///
    /// of the rays' radiance (irradiance texels, power 1: `x̄_n` estimates the cosine-weighted
    /// mean radiance `E(n)/π` for directions spread uniformly) and of their `(t, t²)`
    /// (visibility texels, power 50), then takes one moving-average step toward it — DDGI's
    /// per-frame hysteresis blend, here with ADGI's counted average. Texels no ray reaches keep
    /// their word. Rays with a NaN radiance or a non-finite direction are skipped (a NaN
    /// distance only for visibility); +∞ radiance saturates at the codec's maximum.
    ///
    /// `u` is the caller's uniform; texel k rounds with its `k`-th rotation. Query the result
    /// with [`crate::TexelContent::Irradiance`]. Border texels are not written: call
    /// [`Self::refresh_probe_borders`] before a GPU upload.
    pub fn blend_rays(&self, probe: usize, rays: &[RaySample], weights: &BlendWeights, u: f32) {
        self.blend_rays_with(probe, rays, weights, u, self.config().moving_average);
    }

    /// [`Self::blend_rays`] with another N_max for this blend (a probe whose lighting changed
    /// may forget faster than the others, [`crate::UpdatePolicy::AdgiBlend`]).
    pub fn blend_rays_with(
        &self,
        probe: usize,
        rays: &[RaySample],
        weights: &BlendWeights,
        u: f32,
        average: MovingAverage,
    ) {
        let cap = self.config().irradiance_layout.codec().max_value();
        let mut dirs = Vec::with_capacity(rays.len());
        let mut radiance = Vec::with_capacity(rays.len());
        let mut moments = Vec::with_capacity(rays.len());
        for r in rays {
            let Some(d) = r.direction.try_normalize() else {
                continue;
            };
            dirs.push(d);
            radiance.push(
                (!r.radiance.is_nan()).then(|| r.radiance.clamp(Vec3::ZERO, Vec3::splat(cap))),
            );
            moments.push(
                self.normalise_distance(r.distance)
                    .map(|t| Vec2::new(t, t * t)),
            );
        }
        for (k, &(texel, n, _)) in self.irradiance_tables.interior.iter().enumerate() {
            let mut sum = Vec3::ZERO;
            let mut wsum = 0.0;
            for (d, l) in dirs.iter().zip(&radiance) {
                let Some(l) = l else { continue };
                let c = n.dot(*d);
                if c > 0.0 {
                    let w = pow_weight(c, weights.irradiance_power);
                    sum += w * *l;
                    wsum += w;
                }
            }
            if wsum > BLEND_WEIGHT_EPSILON {
                self.update_irradiance_with(
                    probe,
                    texel as usize,
                    sum / wsum,
                    rotate_uniform(u, k as u32),
                    average,
                );
            }
        }
        let offset = self.irradiance_tables.interior.len() as u32;
        for (k, &(texel, n, _)) in self.visibility_tables.interior.iter().enumerate() {
            let mut sum = Vec2::ZERO;
            let mut wsum = 0.0;
            for (d, m) in dirs.iter().zip(&moments) {
                let Some(m) = m else { continue };
                let c = n.dot(*d);
                if c > 0.0 {
                    let w = pow_weight(c, weights.distance_power);
                    sum += w * *m;
                    wsum += w;
                }
            }
            if wsum > BLEND_WEIGHT_EPSILON {
                self.update_visibility_with(
                    probe,
                    texel as usize,
                    sum / wsum,
                    rotate_uniform(u, offset + k as u32),
                    average,
                );
            }
        }
    }
}

/// `c^p` for `c ∈ (0, 1]`, with the common powers 1 and 50 cheap.
#[inline(always)]
fn pow_weight(c: f32, p: f32) -> f32 {
    if p == 1.0 {
        c
    } else if p == 50.0 {
        let c2 = c * c;
        let c5 = c2 * c2 * c;
        let c10 = c5 * c5;
        let c20 = c10 * c10;
        c20 * c20 * c10
    } else {
        c.powf(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ProbeGrid, TexelConfig};
    use glam::UVec3;
    use mcg_color_codec::{IrradianceLayout, IrradianceWord};
    use rand::{RngExt, SeedableRng};

    fn grid() -> ProbeGrid {
        ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(2, 2, 1)).unwrap()
    }

    #[test]
    fn pow_weight_matches_powf() {
        for c in [0.01f32, 0.3, 0.9, 1.0] {
            for p in [1.0f32, 50.0, 3.5] {
                mcg_test_support::assert_close!(
                    pow_weight(c, p),
                    c.powf(p),
                    1e-5 * c.powf(p) + 1e-30
                );
            }
        }
    }

    #[test]
    fn per_sample_update_lands_in_its_texel() {
        let t = ProbeTexels::new(grid(), TexelConfig::ADGI);
        let d = Vec3::new(0.2, 0.9, -0.3);
        t.update_sample(
            3,
            &RaySample {
                direction: d,
                radiance: Vec3::new(1.0, 0.5, 0.25),
                distance: 0.8,
            },
            0.4,
        );
        let im = t.config().irradiance_map;
        let vm = t.config().visibility_map;
        let ti = im.index(im.texel(d));
        let tv = vm.index(vm.texel(d));
        assert!(
            (t.irradiance(3, ti) - Vec3::new(1.0, 0.5, 0.25))
                .abs()
                .max_element()
                < 0.02
        );
        let tn = 0.8 / 3f32.sqrt();
        let m = t.visibility(3, tv);
        assert!(
            (m - Vec2::new(tn, tn * tn)).abs().max_element() < 2e-3,
            "{m}"
        );
        // Nothing else changed.
        let irr = t.irradiance_words();
        assert_eq!(irr.iter().filter(|&&w| w != 0).count(), 1);
        let vis = t.visibility_words();
        assert_eq!(vis.iter().filter(|&&w| w != 0).count(), 1);
    }

    #[test]
    fn bad_samples_change_nothing_or_saturate() {
        let t = ProbeTexels::new(grid(), TexelConfig::ADGI);
        let s = RaySample {
            direction: Vec3::X,
            radiance: Vec3::new(f32::NAN, 1.0, 1.0),
            distance: f32::NAN,
        };
        t.update_sample(0, &s, 0.5);
        assert!(t.irradiance_words().iter().all(|&w| w == 0));
        assert!(t.visibility_words().iter().all(|&w| w == 0));
        // Zero direction lands somewhere valid, infinite radiance saturates finitely.
        let s = RaySample {
            direction: Vec3::ZERO,
            radiance: Vec3::INFINITY,
            distance: f32::INFINITY,
        };
        t.update_sample(0, &s, 0.5);
        t.blend_rays(
            1,
            &[
                s,
                RaySample {
                    direction: Vec3::NAN,
                    ..s
                },
            ],
            &BlendWeights::DDGI,
            0.5,
        );
        for p in 0..4 {
            for i in 0..64 {
                assert!(t.irradiance(p, i).is_finite());
            }
            for i in 0..256 {
                assert!(t.visibility(p, i).is_finite());
            }
        }
    }

    /// The blend of rays from a constant environment writes L into every interior texel, and the
    /// blend of a single-direction light writes the cosine-weighted mean.
    #[test]
    fn blend_constant_and_lobe() {
        let t = ProbeTexels::new(grid(), TexelConfig::ADGI);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let l = Vec3::new(0.8, 0.4, 0.1);
        let rays: Vec<RaySample> = (0..256)
            .map(|_| {
                let z: f32 = rng.random::<f32>() * 2.0 - 1.0;
                let phi: f32 = rng.random::<f32>() * core::f32::consts::TAU;
                let r = (1.0 - z * z).sqrt();
                RaySample {
                    direction: Vec3::new(r * phi.cos(), r * phi.sin(), z),
                    radiance: l,
                    distance: 1.5,
                }
            })
            .collect();
        t.blend_rays(0, &rays, &BlendWeights::DDGI, 0.3);
        for &(i, _, _) in &t.irradiance_tables.interior {
            assert!((t.irradiance(0, i as usize) - l).abs().max_element() < 0.01 * 0.8 + 1e-3);
        }
        let tn = 1.5 / 3f32.sqrt();
        for &(i, _, _) in &t.visibility_tables.interior {
            let m = t.visibility(0, i as usize);
            assert!(
                (m - Vec2::new(tn, tn * tn)).abs().max_element() < 3e-3,
                "{m}"
            );
        }
    }

    /// Concurrent updates lose nothing: count and value against a serial replay.
    ///
    /// 4 threads (released together by a barrier) apply 50 000 updates each to 2 texels (¾ of them to one) of one probe (stochastic
    /// rounding, a distinct value per update). Each successful compare-and-swap applies the pure
    /// `MovingAverage::update` to the word current at that instant, so the run is correct iff
    /// some serial order of the updates, replayed from word 0, gives every recorded transition
    /// and the final stored word. `update_irradiance` returns `(before, after)` of its swap; the
    /// test checks (1) every record replays: `update(before, value, u) == after`; (2) the
    /// records chain into one serial order from 0 to the stored word — the transitions are the
    /// edges of a multigraph on words, and such an order exists iff they form an Eulerian trail
    /// from 0 to the final word (degree balance + all edges reachable from 0; Euler's theorem);
    /// (3) the count is min(updates, N_max) and all 200 000 calls are recorded. A lost update (a
    /// plain load/store instead of the CAS) breaks (2): two records share a `before` that
    /// occurred once.
    #[test]
    fn concurrent_updates_lose_nothing() {
        use std::collections::HashMap;
        let t = ProbeTexels::new(grid(), TexelConfig::ADGI);
        let config = *t.config();
        let texels = [10usize, 10, 10, 11];
        let threads = 4;
        let per = 50_000;
        let mut log = Vec::new();
        let barrier = std::sync::Barrier::new(threads);
        std::thread::scope(|s| {
            let handles: Vec<_> = (0..threads)
                .map(|th| {
                    let t = &t;
                    let barrier = &barrier;
                    s.spawn(move || {
                        barrier.wait();
                        (0..per)
                            .map(|i| {
                                let texel = texels[(i + th) % 4];
                                let v = Vec3::new(
                                    (0.013 * (th * per + i) as f32) % 5.0,
                                    0.5 + 0.1 * th as f32,
                                    (i % 7) as f32 * 0.2,
                                );
                                let u = rotate_uniform(0.1 * th as f32, i as u32);
                                let (before, after) = t.update_irradiance(2, texel, v, u);
                                (texel, v, u, before, after)
                            })
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            for h in handles {
                log.extend(h.join().unwrap());
            }
        });
        assert_eq!(log.len(), threads * per);
        let layout = IrradianceLayout::ADGI;
        for texel in [10usize, 11] {
            let records: Vec<_> = log.iter().filter(|r| r.0 == texel).collect();
            // (1) each record is one pure moving-average step.
            for &&(_, v, u, before, after) in &records {
                let want = config.moving_average.update(
                    &layout,
                    before,
                    v,
                    config.rounding.with_uniform(u),
                );
                assert_eq!(want, after);
            }
            // (2) Eulerian trail from 0 to the stored word.
            let last = t.irradiance_word(2, texel).0;
            let mut balance: HashMap<u32, i64> = HashMap::new();
            let mut out: HashMap<u32, Vec<u32>> = HashMap::new();
            for &&(_, _, _, before, after) in &records {
                *balance.entry(before).or_default() += 1;
                *balance.entry(after).or_default() -= 1;
                out.entry(before).or_default().push(after);
            }
            *balance.entry(0).or_default() -= 1;
            *balance.entry(last).or_default() += 1;
            assert!(
                balance.values().all(|&b| b == 0),
                "texel {texel}: degrees unbalanced"
            );
            let mut seen = std::collections::HashSet::from([0u32]);
            let mut stack = vec![0u32];
            while let Some(w) = stack.pop() {
                for &n in out.get(&w).map(Vec::as_slice).unwrap_or(&[]) {
                    if seen.insert(n) {
                        stack.push(n);
                    }
                }
            }
            assert!(
                records.iter().all(|r| seen.contains(&r.3)),
                "texel {texel}: disconnected"
            );
            // (3) the count saw every update.
            assert_eq!(
                layout.count(IrradianceWord(last)),
                63.min(records.len() as u32)
            );
        }
    }

    /// Counts see every update: with 16-bit count fields (layouts R6 G5 B5 + 16 and 8/8 + 16,
    /// N_max = 65 535), 4 threads released by a barrier apply 10 000 per-sample updates each to
    /// one texel → count 40 000 in its irradiance and visibility words; and 4 threads × 10 DDGI
    /// blends of one probe → count 40 in every interior texel. A lost update lowers a count.
    #[test]
    fn concurrent_counts_are_exact() {
        use mcg_color_codec::{LogCodec, MovingAverage, VisibilityLayout};
        let config = TexelConfig {
            irradiance_layout: IrradianceLayout::new(6, 5, 5, 16, LogCodec::IRRADIANCE).unwrap(),
            visibility_layout: VisibilityLayout::new(
                8,
                8,
                16,
                LogCodec::DISTANCE,
                LogCodec::SQUARED_DISTANCE,
            )
            .unwrap(),
            moving_average: MovingAverage::new(65_535).unwrap(),
            ..TexelConfig::ADGI
        };
        let t = ProbeTexels::new(grid(), config);
        let rays: Vec<RaySample> = (0..64)
            .map(|i| {
                let z = 1.0 - (2 * i + 1) as f32 / 64.0;
                let phi = i as f32 * 2.399_963;
                let r = (1.0 - z * z).sqrt();
                RaySample {
                    direction: Vec3::new(r * phi.cos(), r * phi.sin(), z),
                    radiance: Vec3::splat(0.5 + 0.01 * i as f32),
                    distance: 0.7,
                }
            })
            .collect();
        let d = Vec3::new(0.3, -0.2, 0.9);
        let barrier = std::sync::Barrier::new(4);
        std::thread::scope(|s| {
            for th in 0..4u32 {
                let t = &t;
                let rays = &rays;
                let barrier = &barrier;
                s.spawn(move || {
                    barrier.wait();
                    for i in 0..10_000u32 {
                        let sample = RaySample {
                            direction: d,
                            radiance: Vec3::splat(th as f32 + 1e-4 * i as f32),
                            distance: 1.0 + 1e-4 * i as f32,
                        };
                        t.update_sample(0, &sample, rotate_uniform(0.3, th * 10_000 + i));
                    }
                    barrier.wait();
                    for i in 0..10 {
                        t.blend_rays(
                            1,
                            rays,
                            &BlendWeights::DDGI,
                            rotate_uniform(0.7, th * 10 + i),
                        );
                    }
                });
            }
        });
        let il = config.irradiance_layout;
        let vl = config.visibility_layout;
        let im = config.irradiance_map;
        let vm = config.visibility_map;
        assert_eq!(
            il.count(t.irradiance_word(0, im.index(im.texel(d)))),
            40_000
        );
        assert_eq!(
            vl.count(t.visibility_word(0, vm.index(vm.texel(d)))),
            40_000
        );
        for &(i, _, _) in &t.irradiance_tables.interior {
            assert_eq!(il.count(t.irradiance_word(1, i as usize)), 40);
        }
        for &(i, _, _) in &t.visibility_tables.interior {
            assert_eq!(vl.count(t.visibility_word(1, i as usize)), 40);
        }
    }

    #[test]
    fn value_stability() {
        let t = ProbeTexels::new(grid(), TexelConfig::ADGI);
        let rays = [
            RaySample {
                direction: Vec3::new(0.1, 0.2, 0.97),
                radiance: Vec3::new(1.0, 0.5, 0.2),
                distance: 0.9,
            },
            RaySample {
                direction: Vec3::new(-0.6, 0.7, 0.3),
                radiance: Vec3::new(0.2, 0.4, 0.8),
                distance: 2.5,
            },
            RaySample {
                direction: Vec3::new(0.3, -0.9, -0.2),
                radiance: Vec3::new(3.0, 2.0, 1.0),
                distance: 0.3,
            },
        ];
        t.blend_rays(0, &rays, &BlendWeights::DDGI, 0.4);
        t.update_sample(1, &rays[1], 0.6);
        let im = t.config().irradiance_map;
        let vm = t.config().visibility_map;
        let words = [
            t.irradiance_word(0, im.index(im.texel(Vec3::Z))).0,
            t.irradiance_word(0, im.index(im.texel(-Vec3::Y))).0,
            t.visibility_word(0, vm.index(vm.texel(rays[0].direction)))
                .0,
            t.irradiance_word(1, im.index(im.texel(rays[1].direction)))
                .0,
            t.visibility_word(1, vm.index(vm.texel(rays[1].direction)))
                .0,
        ];
        assert_eq!(
            words,
            [
                0x0575_ad07,
                0x0636_bf87,
                0x04ed_adea,
                0x0609_8e8e,
                0x05e0_73f8
            ],
            "{words:#x?}"
        );
    }

    #[test]
    fn nearest_probe_rounds_and_clamps() {
        let t = ProbeTexels::new(grid(), TexelConfig::ADGI);
        let g = *t.grid();
        assert_eq!(
            t.nearest_probe(Vec3::new(0.4, 0.6, 0.0)),
            g.probe_index(UVec3::new(0, 1, 0))
        );
        assert_eq!(
            t.nearest_probe(Vec3::new(0.6, 0.4, 3.0)),
            g.probe_index(UVec3::new(1, 0, 0))
        );
        assert_eq!(
            t.nearest_probe(Vec3::new(-9.0, 9.0, 0.0)),
            g.probe_index(UVec3::new(0, 1, 0))
        );
        assert_eq!(t.nearest_probe(Vec3::NAN), 0);
        assert_eq!(
            t.nearest_probe(Vec3::INFINITY),
            g.probe_index(UVec3::new(1, 1, 0))
        );
        let s = RaySample {
            direction: Vec3::X,
            radiance: Vec3::ONE,
            distance: 1.0,
        };
        t.update_sample_at(Vec3::new(0.9, 0.1, 0.0), &s, 0.5);
        let im = t.config().irradiance_map;
        assert_eq!(
            IrradianceLayout::ADGI.count(t.irradiance_word(1, im.index(im.texel(Vec3::X)))),
            1
        );
    }
}
