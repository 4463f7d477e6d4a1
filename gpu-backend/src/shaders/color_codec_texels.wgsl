#define_import_path mcg::color_codec_texels
// mcg-color-codec texel twin: the moving-average update of a packed irradiance or visibility
// texel as a compare-and-swap loop (`MovingAverage::update_atomic`, ADGI sec. 4.5-4.7), on the
// storage array `mcg_codec_texels` bound where the shader defs MCG_CODEC_TEXELS_GROUP and
// MCG_CODEC_TEXELS_BINDING say. Upload `IrradianceWord`s / `VisibilityWord`s
// (`bytemuck::cast_slice`) into it as they are; texel indices are yours (several texel sets
// can share the array at offsets you choose).

#import mcg::color_codec::{CodecRounding, codec_irradiance_update, codec_visibility_update}

@group(#{MCG_CODEC_TEXELS_GROUP}) @binding(#{MCG_CODEC_TEXELS_BINDING})
var<storage, read_write> mcg_codec_texels: array<atomic<u32>>;

// Folds `sample` into texel `texel` and returns the word written. Reads the word, computes
// the update, and publishes it with `atomicCompareExchangeWeak`; when another invocation
// changed the word in between (or the exchange failed spuriously) it retries from the word
// it saw, so every update lands exactly once, in some serial order.
fn codec_irradiance_update_atomic(texel: u32, sample: vec3<f32>, max_count: u32, rounding: CodecRounding) -> u32 {
    var current = atomicLoad(&mcg_codec_texels[texel]);
    var written = current;
    loop {
        written = codec_irradiance_update(current, sample, max_count, rounding);
        if written == current {
            break;
        }
        let r = atomicCompareExchangeWeak(&mcg_codec_texels[texel], current, written);
        if r.exchanged {
            break;
        }
        current = r.old_value;
    }
    return written;
}

// `MovingAverage::update_atomic` on a visibility texel: as `codec_irradiance_update_atomic`.
fn codec_visibility_update_atomic(texel: u32, sample: vec2<f32>, max_count: u32, rounding: CodecRounding) -> u32 {
    var current = atomicLoad(&mcg_codec_texels[texel]);
    var written = current;
    loop {
        written = codec_visibility_update(current, sample, max_count, rounding);
        if written == current {
            break;
        }
        let r = atomicCompareExchangeWeak(&mcg_codec_texels[texel], current, written);
        if r.exchanged {
            break;
        }
        current = r.old_value;
    }
    return written;
}
