// Pack and unpack kernels, used by the parity tests. Composed after the prelude,
// `common.wgsl` and `color_codec.wgsl`. One invocation per element.

@group(0) @binding(0) var<storage, read> values: array<vec4<f32>>;
// Per value: (R11G11B10, RGB9E5, 0, 0).
@group(0) @binding(1) var<storage, read_write> words: array<vec4<u32>>;
// Per value: the unpacked R11G11B10 and RGB9E5 words, (r, g, b, 0) each.
@group(0) @binding(2) var<storage, read_write> decoded: array<vec4<f32>>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn codec_pack_unpack(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&words) {
        return;
    }
    let v = values[i].xyz;
    let w = vec4<u32>(codec_r11g11b10_pack(v), codec_rgb9e5_pack(v), 0u, 0u);
    words[i] = w;
    decoded[2u * i] = vec4<f32>(codec_r11g11b10_unpack(w.x), 0.0);
    decoded[2u * i + 1u] = vec4<f32>(codec_rgb9e5_unpack(w.y), 0.0);
}
