use mcg_markov_guide::toy_renderer::{McpgToyConfig, McpgToyRenderer};
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
        for guided in [true, false] {
            let mut rng = Pcg64Mcg::seed_from_u64(1);
            let mut c = McpgToyConfig::small(guided);
            if std::env::var("NODISCARD").is_ok() {
                c.discard = false;
            }
            if let Ok(v) = std::env::var("RATIO") {
                c.params.discard_ratio = v.parse().unwrap();
            }
            if let Ok(v) = std::env::var("SPP") {
                c.samples_per_pixel = v.parse().unwrap();
            }
            let mut r = McpgToyRenderer::new(c);
            let exact: Vec<f64> = (0..r.pixel_count())
                .map(|i| scene.irradiance(r.shading_point(i)).unwrap())
                .collect();
            let (mut se, mut bias, mut n) = (0.0, 0.0, 0.0);
            let mut frames = vec![];
            let mut lobe = 0.0;
            for frame in 0..1000 {
                let f = r.render_frame(&scene, &mut rng);
                if frame >= 50 {
                    lobe += f.lobe_fraction();
                    let mut fb = 0.0;
                    for (a, b) in f.estimates.iter().zip(&exact) {
                        let d = (*a as f64 - b) / b;
                        se += d * d;
                        bias += d;
                        n += 1.0;
                        fb += d;
                    }
                    frames.push(fb / f.estimates.len() as f64);
                }
            }
            let bm: Vec<f64> = frames
                .chunks(50)
                .map(|c| c.iter().sum::<f64>() / c.len() as f64)
                .collect();
            let m = bm.iter().sum::<f64>() / bm.len() as f64;
            let v = bm.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (bm.len() - 1) as f64;
            println!(
                "{scene_name} guided={guided}: rel MSE {:.4}  rel bias {:.4} ± {:.4}  lobe fraction {:.3} states {}",
                se / n,
                bias / n,
                (v / bm.len() as f64).sqrt(),
                lobe / 950.0,
                r.grids().adaptive_table.len()
            );
        }
    }
}
