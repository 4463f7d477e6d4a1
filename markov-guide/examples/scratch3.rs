use mcg_markov_guide::toy_renderer::{McpgToyConfig, McpgToyRenderer};
use mcg_markov_guide::toy_scene::ToyScene;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

fn main() {
    let speed: f32 = std::env::args().nth(1).unwrap().parse().unwrap();
    let mut scene = ToyScene::moving_light(speed);
    scene.lights[0].vanish = 60.0;
    for (pred, disc) in [(true, true), (false, true), (true, false)] {
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let mut c = McpgToyConfig::small(true);
        c.velocity_prediction = pred;
        c.discard = disc;
        let mut r = McpgToyRenderer::new(c);
        let mut line = String::new();
        for frame in 0..140 {
            let f = r.render_frame(&scene.at_time(frame as f32), &mut rng);
            if frame % 10 == 0 || (frame > 58 && frame < 90 && frame % 3 == 0) {
                line += &format!(
                    " {frame}:{:.3}/{:.2}",
                    f.mean_lobe_angle(),
                    f.lobe_fraction()
                );
            }
        }
        println!("pred={pred} discard={disc}:{line}");
    }
}
