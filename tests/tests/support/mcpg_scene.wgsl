// The plane of shading points lit by up to 8 sphere lights, as a renderer's WGSL would guide it with
// `mcg::mcpg` (the guide bound at group 1): one guided sample per point and frame, the
// irradiance estimate L·cos/p written per point, the chain trained with the observation.
// Modes: 0 MCPG, 2 MCPG dividing by the plain mean of the accessed states'
// densities (eq. 7 read literally, a biased estimator), 3 MCPG without the light's previous
// position (no velocity prediction).

#import mcg::constants::{MCG_FRAC_1_PI, MCG_WORKGROUP_SIZE, MCPG_NO_LOBE}
#import mcg::dispatch::mcg_invocation_index
#import mcg::sampling::{mcg_pcg_hash, mcg_rng_uniform}
#import mcg::mcpg::{
    McpgBeginUniforms, McpgFinishUniforms, McpgSampleUniforms, mcpg_begin, mcpg_finish,
    mcpg_observation_escaped, mcpg_observation_hit, mcpg_params, mcpg_sample,
    mcpg_scatter_pdf, mcpg_surface_vertex
}

struct SceneParams {
    frame: u32,
    seed: u32,
    side: u32,
    mode: u32,
    extent: f32,
    light_count: u32,
    pad_a: u32,
    pad_b: u32,
    // Per light: (centre, radius), (velocity, radiance).
    lights: array<vec4<f32>, 16>,
}

// The nearest light along unit `d` from `o`: (distance, index), distance −1 for a miss.
fn nearest_light(o: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    var best = vec2<f32>(-1.0, 0.0);
    for (var l = 0u; l < scene.light_count; l += 1u) {
        let sphere = scene.lights[2u * l];
        let t = ray_sphere(o, d, sphere.xyz, sphere.w);
        if t > 0.0 && (best.x < 0.0 || t < best.x) {
            best = vec2<f32>(t, f32(l));
        }
    }
    return best;
}

@group(0) @binding(0) var<uniform> scene: SceneParams;
// Per frame and point: (estimate, 1 for a lobe sample).
@group(0) @binding(1) var<storage, read_write> estimates: array<vec2<f32>>;

// Distance along unit `d` from `o` to the sphere, or −1 for a miss.
fn ray_sphere(o: vec3<f32>, d: vec3<f32>, c: vec3<f32>, r: f32) -> f32 {
    let oc = o - c;
    let b = dot(oc, d);
    let h = b * b - (dot(oc, oc) - r * r);
    if h < 0.0 {
        return -1.0;
    }
    let t = -b - sqrt(h);
    return select(-1.0, t, t > 0.0);
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn scene_frame(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    let count = scene.side * scene.side;
    if i >= count {
        return;
    }
    let cell = (vec2<f32>(f32(i % scene.side), f32(i / scene.side)) + 0.5) / f32(scene.side);
    let x = vec3<f32>(scene.extent * (2.0 * cell - 1.0), 0.0);
    let n = vec3<f32>(0.0, 0.0, 1.0);
    var rng = mcg_pcg_hash(i ^ mcg_pcg_hash(scene.frame ^ mcg_pcg_hash(scene.seed)));
    let out = scene.frame * count + i;
    var u: McpgBeginUniforms;
    for (var k = 0u; k < 8u; k += 1u) {
        u.candidates[k] = vec4<f32>(mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng));
    }
    var v = mcpg_begin(mcpg_surface_vertex(x, n), u);
    let choice = mcg_rng_uniform(&rng);
    let s = mcpg_sample(&v, McpgSampleUniforms(choice, vec2<f32>(mcg_rng_uniform(&rng), mcg_rng_uniform(&rng))));
    var pdf = s.pdf;
    if scene.mode == 2u {
        // The trap: the plain mean over the accessed states instead of the w̄-weighted mixture.
        let scatter = mcpg_scatter_pdf(&v, s.direction);
        if v.weight_sum > 0.0 {
            var sum = 0.0;
            var states = 0.0;
            for (var k = 0u; k < v.count; k += 1u) {
                if v.shares[k] > 0.0 {
                    let lobe = v.lobes[k];
                    let dd = s.direction - lobe.mu;
                    sum += v.normalizations[k] * exp(-0.5 * lobe.kappa * dot(dd, dd));
                    states += 1.0;
                }
            }
            let p = mcpg_params.bsdf_probability;
            pdf = p * scatter + (1.0 - p) * (v.scatter_share * scatter + (1.0 - v.scatter_share) * sum / max(states, 1.0));
        }
    }
    let cos = max(dot(n, s.direction), 0.0);
    let hit = nearest_light(x, s.direction);
    var estimate = 0.0;
    let weight = vec3<f32>(cos * MCG_FRAC_1_PI / pdf);
    var obs = mcpg_observation_escaped(vec3<f32>(0.0), weight);
    if hit.x > 0.0 {
        let l = u32(hit.y);
        let sphere = scene.lights[2u * l];
        let motion = scene.lights[2u * l + 1u];
        estimate = motion.w * cos / pdf;
        let y = x + hit.x * s.direction;
        obs = mcpg_observation_hit(y, normalize(y - sphere.xyz), vec3<f32>(motion.w), weight);
        if scene.mode != 3u {
            obs.has_previous = 1u;
            obs.previous_position = y - motion.xyz;
        }
    }
    obs.has_reflected = 1u;
    let f = McpgFinishUniforms(mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng));
    mcpg_finish(&v, s, obs, f);
    estimates[out] = vec2<f32>(estimate, select(1.0, 0.0, s.lobe == MCPG_NO_LOBE));
}
