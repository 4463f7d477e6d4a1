//! A small multi-threaded CPU path tracer with and without MCPG ([`mcpg::Guide`]), on a room
//! whose only light is hidden behind a panel: every pixel is lit indirectly.
//!
//! Lambertian surfaces, `--bounces` scattering events (default 3), no next-event estimation,
//! std threads. It renders a cosine-sampled reference, then cosine sampling and MCPG for the
//! same number of frames, and prints per-frame MSE against the reference, time per frame, the
//! MSE ratio at equal samples and at equal time, the fraction of guided directions that went
//! below the surface, and the pooled z of the accumulated MCPG image against the reference.
//!
//! ```text
//! cargo run -p mcg-markov-guide --release --example guided_room -- [--size 96] [--frames 64]
//!     [--spp 8] [--reference-spp 2048] [--threads 2] [--bounces 3] [--seed 1]
//!     [--hemisphere sphere|product] [--bsdf-probability 0.1] [--no-cache]
//!     [--cache-level-bias 2] [--candidates 5] [--adaptive-capacity 1048576]
//!     [--confidence-samples 0] [--alpha-min 0.01]
//! ```
//!
//! The reference image is kept in the temporary directory between runs (keyed by size,
//! bounces, reference spp and seed). Times are reported as wall clock and as this process's
//! CPU time (from `/proc/self/stat`), which is the steadier measure on a shared machine.
//!
//! ```text
//! ```

use std::f32::consts::PI;
use std::time::Instant;

use mcg_markov_guide::glam::{Vec2, Vec3};
use mcg_markov_guide::mcpg::{
    BeginUniforms, FinishUniforms, Guide, GuideConfig, Hemisphere, Lambertian, SampleUniforms,
    Vertex, VertexObservation,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// An axis-aligned rectangle: `axis` is the constant coordinate at `offset`, the rectangle
/// spans `min..max` in the other two (in x, y, z order).
#[derive(Clone, Copy)]
struct Quad {
    axis: usize,
    offset: f32,
    min: Vec2,
    max: Vec2,
    albedo: Vec3,
    /// Radiance emitted towards `emit_side` (±1 along the axis); zero for non-emitters.
    emitted: Vec3,
    emit_side: f32,
}

struct Hit {
    t: f32,
    quad: usize,
}

struct Scene {
    quads: Vec<Quad>,
}

fn others(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

impl Scene {
    fn quad(axis: usize, offset: f32, min: Vec2, max: Vec2, albedo: Vec3) -> Quad {
        Quad {
            axis,
            offset,
            min,
            max,
            albedo,
            emitted: Vec3::ZERO,
            emit_side: 0.0,
        }
    }

    /// A box from `lo` to `hi` as six quads.
    fn add_box(&mut self, lo: Vec3, hi: Vec3, albedo: Vec3) {
        for axis in 0..3 {
            let (a, b) = others(axis);
            for offset in [lo[axis], hi[axis]] {
                self.quads.push(Self::quad(
                    axis,
                    offset,
                    Vec2::new(lo[a], lo[b]),
                    Vec2::new(hi[a], hi[b]),
                    albedo,
                ));
            }
        }
    }

    /// The unit room: red left wall, green right wall, white elsewhere; a tall and a short box;
    /// a small light on the back wall (0.1 × 0.1, facing +z) behind a 0.3 × 0.3 panel 0.08 in
    /// front of it, so no surface the camera sees is lit directly by much.
    fn room() -> Self {
        let white = Vec3::splat(0.75);
        let mut s = Scene { quads: Vec::new() };
        let full = (Vec2::ZERO, Vec2::ONE);
        s.quads.push(Self::quad(1, 0.0, full.0, full.1, white)); // floor
        s.quads.push(Self::quad(1, 1.0, full.0, full.1, white)); // ceiling
        s.quads.push(Self::quad(2, 0.0, full.0, full.1, white)); // back
        s.quads.push(Self::quad(2, 1.0, full.0, full.1, white)); // front
        s.quads.push(Self::quad(
            0,
            0.0,
            full.0,
            full.1,
            Vec3::new(0.63, 0.06, 0.05),
        )); // left
        s.quads.push(Self::quad(
            0,
            1.0,
            full.0,
            full.1,
            Vec3::new(0.14, 0.45, 0.09),
        )); // right
        s.add_box(Vec3::new(0.15, 0.0, 0.35), Vec3::new(0.4, 0.6, 0.6), white);
        s.add_box(Vec3::new(0.6, 0.0, 0.55), Vec3::new(0.85, 0.3, 0.8), white);
        // The panel, then the light just in front of the back wall.
        s.quads.push(Self::quad(
            2,
            0.08,
            Vec2::new(0.45, 0.55),
            Vec2::new(0.75, 0.85),
            white,
        ));
        s.quads.push(Quad {
            emitted: Vec3::splat(200.0),
            emit_side: 1.0,
            ..Self::quad(
                2,
                0.001,
                Vec2::new(0.55, 0.65),
                Vec2::new(0.65, 0.75),
                Vec3::ZERO,
            )
        });
        s
    }

    fn intersect(&self, o: Vec3, d: Vec3) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for (i, q) in self.quads.iter().enumerate() {
            let denom = d[q.axis];
            if denom == 0.0 {
                continue;
            }
            let t = (q.offset - o[q.axis]) / denom;
            if t.is_nan() || t <= 1e-4 || best.as_ref().is_some_and(|b| t >= b.t) {
                continue;
            }
            let p = o + t * d;
            let (a, b) = others(q.axis);
            if p[a] >= q.min.x && p[a] <= q.max.x && p[b] >= q.min.y && p[b] <= q.max.y {
                best = Some(Hit { t, quad: i });
            }
        }
        best
    }

    /// Normal of `quad` facing against `d`, and the radiance it emits back along −d.
    fn surface(&self, quad: usize, d: Vec3) -> (Vec3, Vec3, Vec3) {
        let q = &self.quads[quad];
        let mut n = Vec3::ZERO;
        n[q.axis] = -d[q.axis].signum();
        let emitted = if n[q.axis] == q.emit_side {
            q.emitted
        } else {
            Vec3::ZERO
        };
        (n, q.albedo, emitted)
    }
}

#[derive(Clone, Copy)]
struct Settings {
    size: usize,
    frames: u32,
    spp: u32,
    reference_spp: u32,
    threads: usize,
    bounces: u32,
    seed: u64,
}

const CAMERA: Vec3 = Vec3::new(0.5, 0.5, 0.98);
/// Vertical field of view in degrees.
const FOV_Y: f32 = 62.0;

fn camera_ray(size: usize, px: usize, py: usize, jitter: Vec2) -> Vec3 {
    let tan = (0.5 * FOV_Y.to_radians()).tan();
    let sx = ((px as f32 + jitter.x) / size as f32 * 2.0 - 1.0) * tan;
    let sy = (1.0 - (py as f32 + jitter.y) / size as f32 * 2.0) * tan;
    Vec3::new(sx, sy, -1.0).normalize()
}

/// Statistics of one guided frame.
#[derive(Default, Clone, Copy)]
struct Counts {
    lobe_samples: u64,
    lobe_below: u64,
}

/// One path from pixel (px, py): cosine sampling when `guide` is `None`, else MCPG.
fn path(
    scene: &Scene,
    guide: Option<&Guide>,
    settings: &Settings,
    px: usize,
    py: usize,
    rng: &mut Pcg64Mcg,
    counts: &mut Counts,
) -> Vec3 {
    let mut d = camera_ray(settings.size, px, py, Vec2::new(rng.random(), rng.random()));
    let Some(first) = scene.intersect(CAMERA, d) else {
        return Vec3::ZERO;
    };
    let mut x = CAMERA + first.t * d;
    let (mut n, mut albedo, emitted) = scene.surface(first.quad, d);
    let mut radiance = emitted;
    let mut throughput = Vec3::ONE;
    for _ in 0..settings.bounces {
        if albedo == Vec3::ZERO {
            break;
        }
        // --- The whole MCPG integration of this tracer: begin, sample, weight, finish. ---
        let (w, weight, next) = match guide {
            None => {
                let (w, pdf) =
                    mcg_markov_guide::cosine_hemisphere(n, Vec2::new(rng.random(), rng.random()));
                let next = scene.intersect(x, w);
                (w, albedo * (n.dot(w).max(0.0) / PI / pdf), next)
            }
            Some(guide) => {
                let candidates = guide.params().candidates as usize;
                let vertex = guide.begin(
                    Vertex::surface(x, n),
                    Lambertian { normal: n },
                    &BeginUniforms::from_fn(candidates, || rng.random()),
                );
                let s = vertex.sample(&SampleUniforms::from_fn(|| rng.random()));
                let cos = n.dot(s.direction);
                if s.lobe.is_some() {
                    counts.lobe_samples += 1;
                    counts.lobe_below += u64::from(cos <= 0.0);
                }
                let weight = if cos > 0.0 && s.pdf > 0.0 {
                    albedo * (cos / PI / s.pdf)
                } else {
                    Vec3::ZERO
                };
                let next = scene.intersect(x, s.direction);
                let observation = match &next {
                    Some(h) => {
                        let (nn, _, le) = scene.surface(h.quad, s.direction);
                        VertexObservation::hit(x + h.t * s.direction, nn, le, weight)
                    }
                    None => VertexObservation::escaped(Vec3::ZERO, weight),
                };
                vertex.finish(&s, &observation, &FinishUniforms::from_fn(|| rng.random()));
                (s.direction, weight, next)
            }
        };
        // --- end of the MCPG part. ---
        throughput *= weight;
        let Some(hit) = next else { break };
        if throughput == Vec3::ZERO {
            break;
        }
        d = w;
        x += hit.t * d;
        let (nn, a, le) = scene.surface(hit.quad, d);
        radiance += throughput * le;
        n = nn;
        albedo = a;
    }
    radiance
}

/// Renders one frame of `spp` samples per pixel on `threads` threads; returns the per-pixel
/// mean and the frame's counts.
fn render_frame(
    scene: &Scene,
    guide: Option<&Guide>,
    settings: &Settings,
    spp: u32,
    frame_seed: u64,
) -> (Vec<Vec3>, Counts) {
    let size = settings.size;
    let mut image = vec![Vec3::ZERO; size * size];
    let mut counts = Counts::default();
    let rows_per_chunk = 4;
    let chunks: Vec<(usize, &mut [Vec3])> = image
        .chunks_mut(size * rows_per_chunk)
        .enumerate()
        .collect();
    let next = std::sync::Mutex::new(chunks.into_iter());
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..settings.threads)
            .map(|_| {
                let next = &next;
                s.spawn(move || {
                    let mut counts = Counts::default();
                    loop {
                        let Some((chunk, rows)) = next.lock().unwrap().next() else {
                            break;
                        };
                        let mut rng = Pcg64Mcg::seed_from_u64(
                            frame_seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ chunk as u64,
                        );
                        for (i, pixel) in rows.iter_mut().enumerate() {
                            let (px, py) = (i % size, chunk * rows_per_chunk + i / size);
                            let mut sum = Vec3::ZERO;
                            for _ in 0..spp {
                                sum += path(scene, guide, settings, px, py, &mut rng, &mut counts);
                            }
                            *pixel = sum / spp as f32;
                        }
                    }
                    counts
                })
            })
            .collect();
        for h in handles {
            let c = h.join().unwrap();
            counts.lobe_samples += c.lobe_samples;
            counts.lobe_below += c.lobe_below;
        }
    });
    (image, counts)
}

/// CPU seconds this process has used (user + system, from `/proc/self/stat`, in clock ticks of
/// 1/100 s); `None` where that file does not exist. On a machine shared with other work the
/// CPU time of a frame measures its cost better than the wall-clock time.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn mse(image: &[Vec3], reference: &[Vec3]) -> f64 {
    image
        .iter()
        .zip(reference)
        .map(|(a, b)| {
            (*a - *b)
                .to_array()
                .iter()
                .map(|&e| f64::from(e) * f64::from(e))
                .sum::<f64>()
                / 3.0
        })
        .sum::<f64>()
        / image.len() as f64
}

/// Per-pixel running sums of frame estimates.
struct Accumulator {
    sum: Vec<[f64; 3]>,
    sum2: Vec<[f64; 3]>,
    frames: u32,
}

impl Accumulator {
    fn new(len: usize) -> Self {
        Self {
            sum: vec![[0.0; 3]; len],
            sum2: vec![[0.0; 3]; len],
            frames: 0,
        }
    }
    fn add(&mut self, image: &[Vec3]) {
        for ((s, s2), p) in self.sum.iter_mut().zip(&mut self.sum2).zip(image) {
            for c in 0..3 {
                let v = p[c] as f64;
                s[c] += v;
                s2[c] += v * v;
            }
        }
        self.frames += 1;
    }
    /// Σ over pixels and channels of the mean and of the variance of the mean.
    fn total_and_variance(&self) -> (f64, f64) {
        let n = self.frames as f64;
        let (mut total, mut var) = (0.0, 0.0);
        for (s, s2) in self.sum.iter().zip(&self.sum2) {
            for c in 0..3 {
                let m = s[c] / n;
                total += m;
                var += (s2[c] / n - m * m).max(0.0) / (n - 1.0);
            }
        }
        (total, var)
    }
}

struct Run {
    mse_late: f64,
    seconds_per_frame: f64,
    cpu_seconds_per_frame: Option<f64>,
    counts: Counts,
    accumulated: Accumulator,
    mse_per_frame: Vec<f64>,
}

fn run(
    scene: &Scene,
    mut guide: Option<Guide>,
    settings: &Settings,
    reference: &[Vec3],
    seed: u64,
) -> Run {
    let size = settings.size;
    let mut accumulated = Accumulator::new(size * size);
    let mut counts = Counts::default();
    let (mut late, mut late_frames, mut seconds, mut cpu) = (0.0, 0, 0.0, Some(0.0));
    let mut mse_per_frame = Vec::new();
    if let Some(g) = &mut guide {
        g.set_camera(CAMERA);
    }
    for frame in 0..settings.frames {
        let start = Instant::now();
        let cpu_start = cpu_seconds();
        let (image, c) = render_frame(
            scene,
            guide.as_ref(),
            settings,
            settings.spp,
            seed * 1_000_003 + frame as u64,
        );
        if let Some(g) = &mut guide {
            g.end_frame();
        }
        let elapsed = start.elapsed().as_secs_f64();
        let cpu_elapsed = cpu_seconds().zip(cpu_start).map(|(b, a)| b - a);
        let e = mse(&image, reference);
        mse_per_frame.push(e);
        if frame >= settings.frames / 2 {
            late += e;
            late_frames += 1;
            seconds += elapsed;
            cpu = cpu.zip(cpu_elapsed).map(|(c, e)| c + e);
            counts.lobe_samples += c.lobe_samples;
            counts.lobe_below += c.lobe_below;
        }
        accumulated.add(&image);
    }
    if let Some(g) = &guide {
        let (a, s) = g.grids();
        println!(
            "  guide occupancy: adaptive {} / {}, static {} / {}, cache {}",
            a.occupied(),
            a.table().capacity(),
            s.occupied(),
            s.table().capacity(),
            g.cache().map_or(0, |c| c.table().count_occupied())
        );
    }
    Run {
        mse_late: late / late_frames as f64,
        seconds_per_frame: seconds / late_frames as f64,
        cpu_seconds_per_frame: cpu.map(|c| c / late_frames as f64),
        counts,
        accumulated,
        mse_per_frame,
    }
}

/// The guide's settings given on the command line (`None`: the default).
struct GuideOptions {
    hemisphere: Hemisphere,
    bsdf_probability: Option<f32>,
    cache: bool,
    level_bias: Option<u32>,
    candidates: Option<u32>,
    adaptive_capacity: Option<u32>,
    confidence_samples: Option<f32>,
    alpha_min: Option<f32>,
}

impl GuideOptions {
    /// The configuration for the room seen by the camera, with these options applied.
    fn config(&self, settings: &Settings) -> GuideConfig {
        let mut config = GuideConfig::for_scene(Vec3::ZERO, Vec3::ONE)
            .for_camera(FOV_Y.to_radians(), settings.size as u32);
        config.hemisphere = self.hemisphere;
        if let Some(p) = self.bsdf_probability {
            config.params.bsdf_probability = p;
        }
        if let Some(n) = self.candidates {
            config.params.candidates = n;
        }
        if let Some(n) = self.adaptive_capacity {
            config.adaptive_capacity = n;
        }
        if let Some(n) = self.confidence_samples {
            config.params.confidence_samples = n;
        }
        if let Some(a) = self.alpha_min {
            config.params.fit.alpha_min = a;
        }
        if !self.cache {
            config.cache = None;
        }
        if let (Some(c), Some(b)) = (&mut config.cache, self.level_bias) {
            c.level_bias = b;
        }
        config
    }
}

/// The settings and guide options from the command line (see the module docs).
fn parse_args() -> (Settings, GuideOptions) {
    let mut settings = Settings {
        size: 96,
        frames: 64,
        spp: 8,
        reference_spp: 2048,
        threads: 2,
        bounces: 3,
        seed: 1,
    };
    let mut options = GuideOptions {
        hemisphere: Hemisphere::CosineProduct,
        bsdf_probability: None,
        cache: true,
        level_bias: None,
        candidates: None,
        adaptive_capacity: None,
        confidence_samples: None,
        alpha_min: None,
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        let value = || args.get(i + 1).cloned().unwrap_or_default();
        match args[i].as_str() {
            "--size" => settings.size = value().parse().expect("--size N"),
            "--frames" => settings.frames = value().parse().expect("--frames N"),
            "--spp" => settings.spp = value().parse().expect("--spp N"),
            "--reference-spp" => {
                settings.reference_spp = value().parse().expect("--reference-spp N")
            }
            "--threads" => settings.threads = value().parse().expect("--threads N"),
            "--bounces" => settings.bounces = value().parse().expect("--bounces N"),
            "--seed" => settings.seed = value().parse().expect("--seed N"),
            "--cache-level-bias" => {
                options.level_bias = Some(value().parse().expect("--cache-level-bias N"))
            }
            "--bsdf-probability" => {
                options.bsdf_probability = Some(value().parse().expect("--bsdf-probability P"))
            }
            "--candidates" => options.candidates = Some(value().parse().expect("--candidates N")),
            "--confidence-samples" => {
                options.confidence_samples =
                    Some(value().parse().expect("--confidence-samples N_c"))
            }
            "--alpha-min" => options.alpha_min = Some(value().parse().expect("--alpha-min A")),
            "--adaptive-capacity" => {
                options.adaptive_capacity = Some(value().parse().expect("--adaptive-capacity N"))
            }
            "--hemisphere" => {
                options.hemisphere = match value().as_str() {
                    "sphere" => Hemisphere::Sphere,
                    _ => Hemisphere::CosineProduct,
                }
            }
            "--no-cache" => {
                options.cache = false;
                i -= 1;
            }
            other => panic!("unknown argument {other}"),
        }
        i += 2;
    }
    (settings, options)
}

/// The reference image: read from the temporary directory when an earlier run stored it (it
/// depends on size, bounces, spp and seed only), else rendered with cosine sampling and stored.
fn reference_image(scene: &Scene, settings: &Settings) -> Vec<Vec3> {
    let start = Instant::now();
    let path = std::env::temp_dir().join(format!(
        "guided_room_reference_{}_{}_{}_{}.f32",
        settings.size, settings.bounces, settings.reference_spp, settings.seed
    ));
    let stored: Option<Vec<Vec3>> = std::fs::read(&path).ok().and_then(|bytes| {
        let floats: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        (floats.len() == 3 * settings.size * settings.size)
            .then(|| floats.chunks_exact(3).map(Vec3::from_slice).collect())
    });
    let reference = match stored {
        Some(r) => r,
        None => {
            let (r, _) = render_frame(
                scene,
                None,
                settings,
                settings.reference_spp,
                u64::MAX - settings.seed,
            );
            let bytes: Vec<u8> = r
                .iter()
                .flat_map(|p| p.to_array())
                .flat_map(f32::to_le_bytes)
                .collect();
            let _ = std::fs::write(&path, bytes);
            r
        }
    };
    println!(
        "reference: {} spp cosine sampling ({}), {:.1} s",
        settings.reference_spp,
        path.display(),
        start.elapsed().as_secs_f64()
    );
    reference
}

fn main() {
    let (settings, options) = parse_args();
    let scene = Scene::room();
    let reference = reference_image(&scene, &settings);
    let config = options.config(&settings);
    let cosine = run(&scene, None, &settings, &reference, settings.seed);
    let guided = run(
        &scene,
        Some(Guide::new(config).expect("valid guide")),
        &settings,
        &reference,
        settings.seed + 17,
    );
    print_comparison(&settings, &cosine, &guided);
}

/// The table of the two runs: late-frame MSE and time per frame, the MSE ratios at equal spp
/// and equal time, the guided lobe samples below the surface, the warm-up ratios, and the
/// accumulated image sums (unbiasedness).
fn print_comparison(settings: &Settings, cosine: &Run, guided: &Run) {
    let half = settings.frames / 2;
    println!(
        "{}x{}, {} frames x {} spp, {} bounces, {} threads; frames {}-{}:",
        settings.size,
        settings.size,
        settings.frames,
        settings.spp,
        settings.bounces,
        settings.threads,
        half + 1,
        settings.frames
    );
    for (name, r) in [("cosine", cosine), ("MCPG", guided)] {
        println!(
            "  {name:6}: per-frame MSE {:.5}, {:.1} ms per frame (wall), {} ms CPU per frame",
            r.mse_late,
            1e3 * r.seconds_per_frame,
            r.cpu_seconds_per_frame
                .map_or("?".to_string(), |c| format!("{:.1}", 1e3 * c))
        );
    }
    let equal_spp = guided.mse_late / cosine.mse_late;
    let equal_time = equal_spp * guided.seconds_per_frame / cosine.seconds_per_frame;
    println!("  MSE ratio MCPG/cosine at equal spp:  {equal_spp:.3}");
    println!("  MSE ratio MCPG/cosine at equal time: {equal_time:.3} (wall clock)");
    if let (Some(g), Some(c)) = (guided.cpu_seconds_per_frame, cosine.cpu_seconds_per_frame) {
        println!(
            "  MSE ratio MCPG/cosine at equal time: {:.3} (CPU time)",
            equal_spp * g / c
        );
    }
    println!(
        "  guided directions below the surface: {:.2} % of {} lobe samples",
        100.0 * guided.counts.lobe_below as f64 / guided.counts.lobe_samples.max(1) as f64,
        guided.counts.lobe_samples
    );
    let warm: Vec<String> = guided
        .mse_per_frame
        .iter()
        .zip(&cosine.mse_per_frame)
        .take(24)
        .map(|(g, c)| format!("{:.2}", g / c))
        .collect();
    println!("  per-frame MSE ratio, frames 1-24: {}", warm.join(" "));
    // Unbiasedness: all frames of both runs accumulated, Σ over pixels and channels.
    let (g, gv) = guided.accumulated.total_and_variance();
    let (c, cv) = cosine.accumulated.total_and_variance();
    println!(
        "  accumulated image sum: MCPG {g:.2} ± {:.2}, cosine {c:.2} ± {:.2}, z = {:.2}; relative difference {:+.3} %",
        gv.sqrt(),
        cv.sqrt(),
        (g - c) / (gv + cv).sqrt(),
        100.0 * (g - c) / c
    );
}
