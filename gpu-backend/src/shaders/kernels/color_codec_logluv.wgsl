// LogLuv32 encode and decode, used by the parity tests. One invocation per element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::color_codec_logluv::{
    codec_logluv32_pack, codec_logluv32_pack_xyz, codec_logluv32_unpack, codec_logluv32_unpack_xyz
}

// Per element: the bits of a colour, read as CIE XYZ and as linear sRGB (xyz), and a word
// to decode (w).
@group(0) @binding(0) var<storage, read> values: array<vec4<u32>>;
// Per element: (pack_xyz(value), pack(value)).
@group(0) @binding(1) var<storage, read_write> packed: array<vec2<u32>>;
// Per element, two entries: unpack_xyz(word) and unpack(word).
@group(0) @binding(2) var<storage, read_write> unpacked: array<vec4<f32>>;
// Binding 3: `mcg_codec_logluv_tables` of `mcg::color_codec_logluv` (MCG_CODEC_LOGLUV_GROUP 0, MCG_CODEC_LOGLUV_BINDING 3).

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn codec_logluv(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&packed) {
        return;
    }
    let v = bitcast<vec3<f32>>(values[i].xyz);
    let word = values[i].w;
    packed[i] = vec2<u32>(codec_logluv32_pack_xyz(v), codec_logluv32_pack(v));
    unpacked[2u * i] = vec4<f32>(codec_logluv32_unpack_xyz(word), 0.0);
    unpacked[2u * i + 1u] = vec4<f32>(codec_logluv32_unpack(word), 0.0);
}
