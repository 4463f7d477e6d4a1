use mcg_markov_guide::glam;
use mcg_markov_guide::toy_renderer::{Decorrelation, McmmToyConfig, McmmToyRenderer, Sampling};
use mcg_markov_guide::toy_scene::ToyScene;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

fn main() {
    let names: Vec<String> = std::env::args().skip(1).collect();
    for scene_name in names {
        let scene = match scene_name.as_str() {
            "large" => ToyScene::large_light(),
            "one" => ToyScene::single_light(),
            _ => ToyScene::eight_lights(),
        };
        for sampling in [
            Sampling::Guided(Decorrelation::Tsmis),
            Sampling::Guided(Decorrelation::Ssmis),
            Sampling::Guided(Decorrelation::Unshuffled),
            Sampling::Cosine,
        ] {
            let mut rng = Pcg64Mcg::seed_from_u64(1);
            let mut c = McmmToyConfig::small(sampling);
            if let Ok(w) = std::env::var("PRIOR") {
                c.params.prior = mcg_markov_guide::mcmm::McmmPrior::LightSize {
                    radius: scene.lights[0].radius,
                    weight: w.parse().unwrap(),
                };
            }
            if let Ok(n) = std::env::var("STEPS") {
                c.steps = n.parse().unwrap();
            }
            let mut r = McmmToyRenderer::new(c);
            let exact: Vec<f64> = (0..r.pixel_count())
                .map(|i| scene.irradiance(r.shading_point(i)).unwrap())
                .collect();
            let (mut se, mut bias, mut n) = (0.0, 0.0, 0.0);
            let mut frames = vec![];
            for frame in 0..2000 {
                let e = r.render_frame(&scene, &mut rng);
                if frame >= 50 {
                    let mut fb = 0.0;
                    for (a, b) in e.iter().zip(&exact) {
                        let d = (*a as f64 - b) / b;
                        se += d * d;
                        bias += d;
                        n += 1.0;
                        fb += d;
                    }
                    frames.push(fb / e.len() as f64);
                }
            }
            let mut hist = vec![0; scene.lights.len() + 1];
            for st in r.states() {
                if !st.is_valid() {
                    hist[scene.lights.len()] += 1;
                    continue;
                }
                let k = scene
                    .lights
                    .iter()
                    .enumerate()
                    .min_by(|a, b| {
                        (a.1.center - st.stats.mean_target)
                            .length()
                            .total_cmp(&(b.1.center - st.stats.mean_target).length())
                    })
                    .unwrap()
                    .0;
                hist[k] += 1;
            }
            println!("targets {hist:?}");
            let ns: Vec<u32> = r.states().iter().map(|s| s.stats.sample_count).collect();
            let ks: Vec<i32> = r
                .states()
                .iter()
                .filter_map(|s| s.lobe_with(glam::Vec3::ZERO, &r.config().params.prior))
                .map(|l| l.kappa() as i32)
                .collect();
            println!("N {ns:?}\nkappa {ks:?}");
            // batch means for the standard error (batches of 50 frames)
            let bm: Vec<f64> = frames
                .chunks(50)
                .map(|c| c.iter().sum::<f64>() / c.len() as f64)
                .collect();
            let m = bm.iter().sum::<f64>() / bm.len() as f64;
            let v = bm.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (bm.len() - 1) as f64;
            println!(
                "{scene_name} {sampling:?}: rel MSE {:.4}  rel bias {:.4} ± {:.4} (batch means)",
                se / n,
                bias / n,
                (v / bm.len() as f64).sqrt()
            );
        }
    }
}
