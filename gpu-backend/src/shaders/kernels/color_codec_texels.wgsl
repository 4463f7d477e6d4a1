// Concurrent moving-average updates of shared irradiance texels, used by the parity tests. One
// invocation per update.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::color_codec::CodecRounding
#import mcg::color_codec_texels::{codec_irradiance_update_atomic, codec_visibility_update_atomic}

struct TexelUpdate {
    sample: vec3<f32>,
    texel: u32,
}

struct TexelParams {
    max_count: u32,
    rounding_mode: u32,
    rounding_u: f32,
    // 0: irradiance words, 1: visibility words (the sample's xy).
    word_layout: u32,
}

// Binding 0: `mcg_codec_texels` of `mcg::color_codec_texels` (MCG_CODEC_TEXELS_GROUP 0, MCG_CODEC_TEXELS_BINDING 0).
@group(0) @binding(1) var<storage, read> updates: array<TexelUpdate>;
@group(0) @binding(2) var<uniform> params: TexelParams;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn codec_texel_updates(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&updates) {
        return;
    }
    let up = updates[i];
    let rounding = CodecRounding(params.rounding_mode, params.rounding_u);
    if params.word_layout == 0u {
        codec_irradiance_update_atomic(up.texel, up.sample, params.max_count, rounding);
    } else {
        codec_visibility_update_atomic(up.texel, up.sample.xy, params.max_count, rounding);
    }
}
