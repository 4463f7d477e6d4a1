// The steps of `GpuProbeChains`, one entry point per dispatch, on the chains' group (group 0).

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::math::{mcg_is_finite3, mcg_is_nan}
#import mcg::color_codec::codec_heuristics_decode
#import mcg::adgi_chains::{
    AdgiChainGrid, AdgiChainState, AdgiLocated, AdgiProbeSample, adgi_chain_uniforms, adgi_guiding_value,
    adgi_locate, adgi_octant, adgi_propose, adgi_uniform_state
}

// The chains' constants (`GpuChainParams` on the host, 160 bytes).
struct AdgiChainParams {
    origin: vec3<f32>,
    probe_count: u32,
    spacing: vec3<f32>,
    pad_d: u32,
    counts: vec3<u32>,
    pad_e: u32,
    lo: vec3<f32>,
    block: u32,
    extent: vec3<f32>,
    chain_count: u32,
    position_step: vec3<f32>,
    direction_step: f32,
    cell_counts: vec3<u32>,
    dedup: u32,
    iterations: u32,
    burn_in: u32,
    seed: u32,
    capacity: u32,
    alpha: f32,
    exponent_cap: f32,
    has_feedback: u32,
    field: u32,
    count: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

// A point and direction at which to evaluate h (`GpuGuideQuery`, 32 bytes; `w` unused).
struct AdgiGuideQuery {
    position: vec4<f32>,
    direction: vec4<f32>,
}

@group(0) @binding(0) var<uniform> chain_params: AdgiChainParams;
@group(0) @binding(1) var<storage, read> chain_words: array<u32>;
@group(0) @binding(2) var<storage, read_write> chain_guide: array<f32>;
@group(0) @binding(3) var<storage, read> chain_feedback: array<f32>;
@group(0) @binding(4) var<storage, read_write> chain_states: array<AdgiChainState>;
@group(0) @binding(5) var<storage, read_write> chain_samples: array<AdgiProbeSample>;
// [0] samples written, [1] proposals, [2] accepted, [3] restarts, [4] dropped, [5..8) unused;
// from [8], one bit per (cell, octant): claimed this frame (dynamic chains, sec. 4.9).
@group(0) @binding(6) var<storage, read_write> chain_counters: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read> chain_queries: array<AdgiGuideQuery>;
@group(0) @binding(8) var<storage, read_write> chain_values: array<f32>;

fn chain_grid() -> AdgiChainGrid {
    let p = chain_params;
    return AdgiChainGrid(p.origin, p.spacing, p.counts, p.block, p.cell_counts, p.lo, p.extent);
}

// h at a located point (`GuidingFunction::value` of its cell and octant; 0 outside the
// domain).
fn chain_target(at: AdgiLocated) -> f32 {
    if !at.inside {
        return 0.0;
    }
    let i = at.cell * 8u + at.octant;
    var g = 0.0;
    if chain_params.has_feedback != 0u {
        g = chain_feedback[i];
    }
    return adgi_guiding_value(chain_guide[i], g, chain_params.alpha, chain_params.exponent_cap);
}

fn chain_locate(s: AdgiChainState) -> AdgiLocated {
    return adgi_locate(s.position, s.z, s.phi, chain_grid());
}

// The guide's table: one heuristic (0 f_v, 1 f_s, 2 f_d) of the heuristics words
// (`guiding_function::decode_field`), max-pooled over each cell's probes
// (`ProxyGrid::max_pool`: NaN skipped, floor 0; ADGI sec. 4.9); a cell of one probe copies it.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_guide_table(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    let cc = chain_params.cell_counts;
    if i >= cc.x * cc.y * cc.z * 8u {
        return;
    }
    let cell = i / 8u;
    let o = i % 8u;
    let counts = chain_params.counts;
    let field = min(chain_params.field, 2u);
    let lo = vec3<u32>(cell % cc.x, (cell / cc.x) % cc.y, cell / (cc.x * cc.y)) * chain_params.block;
    let hi = min(lo + vec3<u32>(chain_params.block), counts);
    var m = 0.0;
    for (var z = lo.z; z < hi.z; z += 1u) {
        for (var y = lo.y; y < hi.y; y += 1u) {
            for (var x = lo.x; x < hi.x; x += 1u) {
                let v = codec_heuristics_decode(chain_words[(x + counts.x * (y + counts.y * z)) * 8u + o])[field];
                if !mcg_is_nan(v) {
                    m = max(m, v);
                }
            }
        }
    }
    chain_guide[i] = m;
}

// h(p, ω) at `chain_params.count` queries (`GuidingFunction::guiding_value`).
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_guide_values(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= chain_params.count {
        return;
    }
    let q = chain_queries[i];
    var at = adgi_locate(q.position.xyz, 1.0, 0.0, chain_grid());
    at.octant = adgi_octant(q.direction.xyz);
    var h = 0.0;
    if mcg_is_finite3(q.direction.xyz) {
        h = chain_target(at);
    }
    chain_values[i] = h;
}

// One frame of every chain (ADGI Alg. 1 with Alg. 5; `ProbeChains::step_frame_parallel` with
// the uniforms of `adgi_chain_uniforms`): re-evaluate h at the persisted state, restart
// uniformly where it is 0 (one draw), then M steps; after the first K, emit the state as a
// sample when h > 0 and it lies in the domain — for dynamic chains only the first claim of a
// (cell, octant) this frame (sec. 4.9).
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_chain_frame(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let j = mcg_invocation_index(id, groups);
    let p = chain_params;
    if j >= p.chain_count {
        return;
    }
    var s = chain_states[j];
    var current = chain_locate(s);
    s.target_value = chain_target(current);
    s.accepted = 0u;
    s.restarted = 0u;
    var draw = 0u;
    var proposals = 0u;
    var accepted = 0u;
    var dropped = 0u;
    if s.target_value == 0.0 {
        let u = adgi_chain_uniforms(p.seed, j, draw);
        draw += 1u;
        s = adgi_uniform_state(u.proposal, chain_grid());
        s.restarted = 1u;
        current = chain_locate(s);
        s.target_value = chain_target(current);
    }
    for (var i = 0u; i < p.iterations; i += 1u) {
        let u = adgi_chain_uniforms(p.seed, j, draw);
        draw += 1u;
        let y = adgi_propose(s, u.proposal, p.position_step, p.direction_step);
        let proposed = chain_locate(y);
        let h = chain_target(proposed);
        proposals += 1u;
        // Alg. 5: accept with probability min(1, h'/h), as ε · h < h' (any h' > 0 when h = 0).
        if h > 0.0 && u.accept * s.target_value < h {
            s.position = y.position;
            s.z = proposed.folded.x;
            s.phi = proposed.folded.y;
            s.target_value = h;
            current = proposed;
            accepted += 1u;
            if i < 32u {
                s.accepted |= 1u << i;
            }
        }
        if i < p.burn_in {
            continue;
        }
        if !current.inside || !(s.target_value > 0.0) {
            dropped += 1u;
            continue;
        }
        let key = current.cell * 8u + current.octant;
        if p.dedup != 0u {
            let bit = 1u << (key % 32u);
            if (atomicOr(&chain_counters[8u + key / 32u], bit) & bit) != 0u {
                dropped += 1u;
                continue;
            }
        }
        let slot = atomicAdd(&chain_counters[0], 1u);
        if slot < p.capacity {
            chain_samples[slot] = AdgiProbeSample(current.position, current.cell, current.direction, s.target_value, current.probe, current.octant, j, i);
        }
    }
    chain_states[j] = s;
    atomicAdd(&chain_counters[1], proposals);
    atomicAdd(&chain_counters[2], accepted);
    atomicAdd(&chain_counters[3], s.restarted);
    atomicAdd(&chain_counters[4], dropped);
}
