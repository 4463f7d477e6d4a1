// A renderer's own kernel using the MCPG guide: its I/O at group 0, the guide at group 1
// (composed with `GpuMcpgGuide::shader_defs(1)`). One guided vertex per input: begin, sample,
// the pdf at a probe direction, and (except in `mcpg_sample_only`) finish. The serial kernel
// begins every input's vertex into the same variable (`mcpg_begin_at`, as a tracer reuses its
// path's vertex), so what one vertex leaves there must not reach the next.

#import mcg::constants::{MCG_WORKGROUP_SIZE, MCPG_NO_LOBE}
#import mcg::dispatch::mcg_invocation_index
#import mcg::markov::MarkovGridState
#import mcg::mcpg::{
    McpgBeginUniforms, McpgFinishUniforms, McpgGuidedVertex, McpgObservation, McpgSampleUniforms,
    McpgVertex, mcpg_begin_at, mcpg_choose_mixture, mcpg_finish, mcpg_load_state, mcpg_pdf,
    mcpg_sample, mcpg_sample_lobe, mcpg_scatter_sample, mcpg_store_state, mcpg_volume_vertex
}

struct StepInput {
    vertex: McpgVertex,
    begin: McpgBeginUniforms,
    // choice, direction x, direction y, unused
    sample: vec4<f32>,
    // accept, store grid, store level, store corner
    finish: vec4<f32>,
    // cache corner, probe direction
    cache_and_probe: vec4<f32>,
    observation: McpgObservation,
}

struct StepOutput {
    direction: vec3<f32>,
    pdf: f32,
    probe_pdf: f32,
    lobe: u32,
    selected: u32,
    transition: u32,
    weight_sum: f32,
    count: u32,
    target_level: u32,
    normal_class: u32,
    // `GuidedVertex::sample_mixture` of the same uniforms, and its lobe.
    mixture: vec3<f32>,
    mixture_lobe: u32,
}

@group(0) @binding(0) var<storage, read> inputs: array<StepInput>;
@group(0) @binding(1) var<storage, read_write> outputs: array<StepOutput>;

fn step(i: u32, finish: bool, v: ptr<function, McpgGuidedVertex>) {
    let input = inputs[i];
    mcpg_begin_at(input.vertex, input.begin, v);
    let s = mcpg_sample(v, McpgSampleUniforms(input.sample.x, input.sample.yz));
    let probe = input.cache_and_probe.yzw;
    let k = mcpg_choose_mixture(v, input.sample.x);
    var mixture = mcpg_scatter_sample(v, input.sample.yz);
    if k != MCPG_NO_LOBE {
        mixture = mcpg_sample_lobe(v, k, input.sample.yz);
    }
    var out = StepOutput(s.direction, s.pdf, mcpg_pdf(v, probe), s.lobe, (*v).selected, 0xffffffffu, (*v).weight_sum, (*v).count, (*v).target_level, (*v).normal_class, mixture, k);
    if finish {
        let f = input.finish;
        out.transition = mcpg_finish(v, s, input.observation, McpgFinishUniforms(f.x, f.y, f.z, f.w, input.cache_and_probe.x));
    }
    outputs[i] = out;
}

@compute @workgroup_size(1)
fn mcpg_steps_serial() {
    var v: McpgGuidedVertex;
    for (var i = 0u; i < arrayLength(&inputs); i += 1u) {
        step(i, true, &v);
    }
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn mcpg_steps_parallel(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&inputs) {
        var v: McpgGuidedVertex;
        step(i, true, &v);
    }
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn mcpg_sample_only(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&inputs) {
        var v: McpgGuidedVertex;
        step(i, false, &v);
    }
}

// Racing stores of whole states into four adaptive slots while reading others: each invocation
// writes states whose eight words all derive from one number; a read that mixes two writes
// counts in `outputs[0].count`, reads that saw a state in `outputs[0].target_level`.
fn state_of(n: u32) -> MarkovGridState {
    let f = f32(n + 1u);
    return MarkovGridState(f, f, f, f, f, f, n, n);
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn mcpg_race(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    var mixed = 0u;
    var seen = 0u;
    for (var r = 0u; r < 64u; r += 1u) {
        mcpg_store_state(false, (i + r) % 4u, state_of(i * 64u + r));
        var s: MarkovGridState;
        if mcpg_load_state(false, (i + r + 1u) % 4u, &s) {
            seen += 1u;
            let f = s.weight_sum;
            let n = u32(f) - 1u;
            if s.mean_target_x != f || s.mean_target_y != f || s.mean_target_z != f || s.one_minus_mean_cosine != f || s.time != f || s.velocity_xy != n || s.velocity_z_count != n {
                mixed += 1u;
            }
        }
    }
    outputs[i].count = mixed;
    outputs[i].target_level = seen;
}

// Stores `state_of(6)` into adaptive slot 0 (one invocation).
@compute @workgroup_size(1)
fn mcpg_store_one() {
    mcpg_store_state(false, 0u, state_of(6u));
}

// Loads adaptive slots 0..4: `selected` 1 when the load succeeded, `weight_sum` the state's w̄.
@compute @workgroup_size(1)
fn mcpg_loads() {
    for (var i = 0u; i < 4u; i += 1u) {
        var s: MarkovGridState;
        let ok = mcpg_load_state(false, i, &s);
        outputs[i].selected = select(0u, 1u, ok);
        outputs[i].weight_sum = s.weight_sum;
    }
}

// `mcpg_volume_vertex(position, view = vertex.normal, jitter = sample.yz)`: the key direction,
// `has_normal` in `selected` and the scatter code in `lobe`.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn mcpg_volume_keys(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&inputs) {
        let input = inputs[i];
        let v = mcpg_volume_vertex(input.vertex.position, input.vertex.normal, input.sample.yz);
        outputs[i].direction = v.key_direction;
        outputs[i].selected = v.has_normal;
        outputs[i].lobe = v.scatter;
    }
}
