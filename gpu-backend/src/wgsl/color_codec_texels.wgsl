// mcg-color-codec texel twin: the moving-average update of a packed irradiance or visibility
// texel as a compare-and-swap loop (`MovingAverage::update_atomic`, ADGI sec. 4.5-4.7). Needs the
// prelude and `color_codec.wgsl`, and a texel array the including shader declares:
//
//     @group(0) @binding(0) var<storage, read_write> codec_texels: array<atomic<u32>>;
//
// Upload `IrradianceWord`s / `VisibilityWord`s (`bytemuck::cast_slice`) into it as they are.

// Folds `sample` into texel `texel` and returns the word written. Reads the word, computes
// the update, and publishes it with `atomicCompareExchangeWeak`; when another invocation
// changed the word in between (or the exchange failed spuriously) it retries from the word
// it saw, so every update lands exactly once, in some serial order.
fn codec_irradiance_update_atomic(texel: u32, sample: vec3<f32>, max_count: u32, rounding: CodecRounding) -> u32 {
    var current = atomicLoad(&codec_texels[texel]);
    var written = current;
    loop {
        written = codec_irradiance_update(current, sample, max_count, rounding);
        if written == current {
            break;
        }
        let r = atomicCompareExchangeWeak(&codec_texels[texel], current, written);
        if r.exchanged {
            break;
        }
        current = r.old_value;
    }
    return written;
}

// `MovingAverage::update_atomic` on a visibility texel: as `codec_irradiance_update_atomic`.
fn codec_visibility_update_atomic(texel: u32, sample: vec2<f32>, max_count: u32, rounding: CodecRounding) -> u32 {
    var current = atomicLoad(&codec_texels[texel]);
    var written = current;
    loop {
        written = codec_visibility_update(current, sample, max_count, rounding);
        if written == current {
            break;
        }
        let r = atomicCompareExchangeWeak(&codec_texels[texel], current, written);
        if r.exchanged {
            break;
        }
        current = r.old_value;
    }
    return written;
}
