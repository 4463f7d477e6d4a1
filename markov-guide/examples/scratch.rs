use mcg_markov_guide::toy_renderer::{Decorrelation, McmmToyConfig, McmmToyRenderer, Sampling};
use mcg_markov_guide::toy_scene::ToyScene;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

fn main() {
    for scene_name in ["one", "eight"] {
        let scene = if scene_name == "one" {
            ToyScene::single_light()
        } else {
            ToyScene::eight_lights()
        };
        for sampling in [
            Sampling::Guided(Decorrelation::Tsmis),
            Sampling::Guided(Decorrelation::Ssmis),
            Sampling::Guided(Decorrelation::Unshuffled),
            Sampling::Cosine,
        ] {
            let mut rng = Pcg64Mcg::seed_from_u64(1);
            let mut r = McmmToyRenderer::new(McmmToyConfig::small(sampling));
            let exact: Vec<f64> = (0..r.pixel_count())
                .map(|i| scene.irradiance(r.shading_point(i)).unwrap())
                .collect();
            let (mut se, mut bias, mut n) = (0.0, 0.0, 0.0);
            for frame in 0..400 {
                let e = r.render_frame(&scene, &mut rng);
                if frame >= 50 {
                    for (a, b) in e.iter().zip(&exact) {
                        let d = (*a as f64 - b) / b;
                        se += d * d;
                        bias += d;
                        n += 1.0;
                    }
                }
            }
            println!(
                "{scene_name} {sampling:?}: rel MSE {:.4}  rel bias {:.4} ± {:.4}",
                se / n,
                bias / n,
                (se / n / n).sqrt()
            );
        }
    }
}
