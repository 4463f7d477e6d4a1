// One guided path vertex per invocation, as a renderer's kernel runs it with `mcg::mcpg` (the
// guide at group 1): a shading point on a plane, MCPG's begin, sample (with its exact pdf), an
// analytic trace to one sphere light, finish; `unfinished_vertex` the same without the finish
// (Alg. 3's update and store, the cache's add: their cost is the difference); `cosine_vertex`
// is the same kernel with cosine sampling and no guide; `reads_vertex` only finds and reads
// the N_mc candidates' states, as `mcpg_begin` does (the reads no implementation of Alg. 1
// avoids: a floor under `guided_vertex`);
// `launch_vertex` only writes its output (the cost of the dispatch, the bounds check and the
// store that every kernel pays).

#import mcg::constants::{HASHGRID_NO_SLOT, MCG_FRAC_1_PI, MCG_PI, MCG_WORKGROUP_SIZE}
#import mcg::hashgrid::{hashgrid_normal_class, hashgrid_target_level}
#import mcg::markov::MarkovGridState
#import mcg::dispatch::mcg_invocation_index
#import mcg::sampling::{mcg_cosine_hemisphere_sample, mcg_pcg_hash, mcg_rng_uniform}
#import mcg::mcpg::{
    McpgBeginUniforms, McpgFinishUniforms, McpgGuidedVertex, McpgSampleUniforms, mcpg_begin_at, mcpg_find,
    mcpg_finish, mcpg_frame, mcpg_key, mcpg_load_state, mcpg_observation_escaped, mcpg_observation_hit,
    mcpg_params, mcpg_sample, mcpg_surface_vertex, mcpg_table
}

const SIDE: u32 = 256u;

@group(0) @binding(0) var<storage, read_write> estimates: array<f32>;

fn light_hit(o: vec3<f32>, d: vec3<f32>) -> f32 {
    let oc = o - vec3<f32>(0.0, 0.0, 3.0);
    let b = dot(oc, d);
    let h = b * b - (dot(oc, oc) - 0.0625);
    if h < 0.0 {
        return -1.0;
    }
    return -b - sqrt(h);
}

fn point(i: u32) -> vec3<f32> {
    return vec3<f32>(2.0 * (vec2<f32>(f32(i % SIDE), f32(i / SIDE)) + 0.5) / f32(SIDE) - 1.0, 0.0);
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn guided_vertex(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    vertex(id, groups, true);
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn unfinished_vertex(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    vertex(id, groups, false);
}

// `guided_vertex`'s body; `finish` false leaves out `mcpg_finish` (`unfinished_vertex`).
fn vertex(id: vec3<u32>, groups: vec3<u32>, finish: bool) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&estimates) {
        return;
    }
    let x = point(i);
    let n = vec3<f32>(0.0, 0.0, 1.0);
    var rng = mcg_pcg_hash(i ^ mcg_pcg_hash(mcpg_frame()));
    var u: McpgBeginUniforms;
    for (var k = 0u; k < 8u; k += 1u) {
        u.candidates[k] = vec4<f32>(mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng));
    }
    var v: McpgGuidedVertex;
    mcpg_begin_at(mcpg_surface_vertex(x, n), u, &v);
    let choice = mcg_rng_uniform(&rng);
    let s = mcpg_sample(&v, McpgSampleUniforms(choice, vec2<f32>(mcg_rng_uniform(&rng), mcg_rng_uniform(&rng))));
    let cos = max(dot(n, s.direction), 0.0);
    let t = light_hit(x, s.direction);
    let weight = vec3<f32>(cos * MCG_FRAC_1_PI / s.pdf);
    var obs = mcpg_observation_escaped(vec3<f32>(0.0), weight);
    var e = 0.0;
    if t > 0.0 {
        e = 40.0 * cos / s.pdf;
        let y = x + t * s.direction;
        obs = mcpg_observation_hit(y, normalize(y - vec3<f32>(0.0, 0.0, 3.0)), vec3<f32>(40.0), weight);
    }
    let f = McpgFinishUniforms(mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng));
    if finish {
        mcpg_finish(&v, s, obs, f);
    }
    estimates[i] = e;
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn cosine_vertex(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&estimates) {
        return;
    }
    let x = point(i);
    let n = vec3<f32>(0.0, 0.0, 1.0);
    var rng = mcg_pcg_hash(i ^ mcg_pcg_hash(mcpg_frame()));
    let d = mcg_cosine_hemisphere_sample(n, vec2<f32>(mcg_rng_uniform(&rng), mcg_rng_uniform(&rng))).direction;
    estimates[i] = select(0.0, 40.0 * MCG_PI, light_hit(x, d) > 0.0);
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn reads_vertex(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&estimates) {
        return;
    }
    let x = point(i);
    let n = vec3<f32>(0.0, 0.0, 1.0);
    let frame = mcpg_frame();
    var rng = mcg_pcg_hash(i ^ mcg_pcg_hash(frame));
    let normal_class = hashgrid_normal_class(n);
    let level = hashgrid_target_level(mcpg_params.levels, distance(mcpg_params.camera, x));
    var sum = 0.0;
    for (var k = 0u; k < mcpg_params.candidates; k += 1u) {
        let key = mcpg_key(x, normal_class, level, mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng));
        let slot = mcpg_find(mcpg_table(key.is_static), key.key, false, frame);
        var state: MarkovGridState;
        if slot != HASHGRID_NO_SLOT && mcpg_load_state(key.is_static, slot, &state) {
            sum += state.weight_sum;
        }
    }
    estimates[i] = sum;
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn launch_vertex(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&estimates) {
        return;
    }
    estimates[i] = f32(i);
}
