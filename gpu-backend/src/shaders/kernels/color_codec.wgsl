// Pack and unpack kernels, used by the parity tests. One invocation per element.

#import mcg::constants::{
    CODEC_ROUND_DOWN, CODEC_ROUND_NEAREST, CODEC_ROUND_STOCHASTIC, MCG_WORKGROUP_SIZE
}
#import mcg::dispatch::mcg_invocation_index
#import mcg::color_codec::{
    CodecRounding, codec_gamma5_pack, codec_gamma5_unpack, codec_heuristics_decode,
    codec_heuristics_encode, codec_irradiance_decode, codec_irradiance_encode, codec_r11g11b10_pack,
    codec_r11g11b10_unpack, codec_rgb9e5_pack, codec_rgb9e5_unpack, codec_visibility_decode,
    codec_visibility_encode
}

// Per element: a colour (xyz) and a uniform for stochastic rounding (w).
@group(0) @binding(0) var<storage, read> values: array<vec4<f32>>;
// Per element, three entries: (R11G11B10, RGB9E5, gamma-5, irradiance round-down with count
// i mod 64) and (irradiance nearest, irradiance stochastic(w), 0, 0).
@group(0) @binding(1) var<storage, read_write> words: array<vec4<u32>>;
// Per element, six entries: the unpacked R11G11B10, RGB9E5, gamma-5, irradiance
// (round-down, nearest), visibility (nearest; xy) and heuristics (nearest) words.
@group(0) @binding(2) var<storage, read_write> decoded: array<vec4<f32>>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn codec_pack_unpack(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&values) {
        return;
    }
    let v = values[i].xyz;
    let u = values[i].w;
    let w0 = vec4<u32>(
        codec_r11g11b10_pack(v),
        codec_rgb9e5_pack(v),
        codec_gamma5_pack(v),
        codec_irradiance_encode(v, i % 64u, CodecRounding(CODEC_ROUND_DOWN, 0.0)),
    );
    let w1 = vec4<u32>(
        codec_irradiance_encode(v, i % 64u, CodecRounding(CODEC_ROUND_NEAREST, 0.0)),
        codec_irradiance_encode(v, i % 64u, CodecRounding(CODEC_ROUND_STOCHASTIC, u)),
        codec_visibility_encode(v.xy, i % 64u, CodecRounding(CODEC_ROUND_NEAREST, 0.0)),
        codec_visibility_encode(v.xy, i % 64u, CodecRounding(CODEC_ROUND_STOCHASTIC, u)),
    );
    words[3u * i] = w0;
    words[3u * i + 1u] = w1;
    let h = min(v, vec3<f32>(1.0));
    let w2 = vec4<u32>(
        codec_heuristics_encode(h, i % 64u, CodecRounding(CODEC_ROUND_NEAREST, 0.0)),
        codec_heuristics_encode(h, i % 64u, CodecRounding(CODEC_ROUND_STOCHASTIC, u)),
        0u,
        0u,
    );
    words[3u * i + 2u] = w2;
    decoded[7u * i + 6u] = codec_heuristics_decode(w2.x);
    decoded[7u * i] = vec4<f32>(codec_r11g11b10_unpack(w0.x), 0.0);
    decoded[7u * i + 1u] = vec4<f32>(codec_rgb9e5_unpack(w0.y), 0.0);
    decoded[7u * i + 2u] = vec4<f32>(codec_gamma5_unpack(w0.z), 0.0);
    decoded[7u * i + 3u] = vec4<f32>(codec_irradiance_decode(w0.w), 0.0);
    decoded[7u * i + 4u] = vec4<f32>(codec_irradiance_decode(w1.x), 0.0);
    decoded[7u * i + 5u] = vec4<f32>(codec_visibility_decode(w1.z), 0.0, 0.0);
}
