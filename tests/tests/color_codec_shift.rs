//! Colour shift of ADGI's unequal 9/9/8 split against equal 10/10/10 log channels and
//! R11G11B10 (the RTXGI DDGI SDK moved to equal channels because unequal precision
//! shifted colours), on a palette of saturated and dark colours.
//!
//! Metrics per colour: hue error = angle between the decoded and the true RGB vector (degrees),
//! luminance error = |Ŷ/Y − 1| with Rec. 709 weights. Checks: every hue error is within the
//! bound implied by the per-channel error bounds (angle ≤ asin(‖bound‖/‖rgb‖)); the mean hue
//! error of 9/9/8 is larger than that of 10/10/10 (both rounded down, as ADGI does), and the
//! 8-bit blue channel carries a larger mean relative error than the 9-bit red and green.

// Channel-indexed loops (`for c in 0..3`) read like the math.
#![allow(clippy::needless_range_loop)]

use mcg_color_codec::glam::Vec3;
use mcg_color_codec::{ColorCodec, IrradianceLayout, LogRgb, R11G11B10, Rounding};

fn palette() -> Vec<Vec3> {
    let hues = [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 0.5, 0.1),
        Vec3::new(0.2, 0.4, 1.0),
        Vec3::new(0.8, 0.6, 0.5),
        Vec3::new(0.3, 0.9, 0.4),
        Vec3::new(0.9, 0.1, 0.4),
        Vec3::new(0.55, 0.5, 0.45),
    ];
    let mut colours = Vec::new();
    for h in hues {
        // Saturated primaries keep a small floor so that hue is defined for every channel.
        let h = h.max(Vec3::splat(0.04));
        for intensity in [4.0, 1.0, 0.25, 0.06, 0.02] {
            colours.push(h * intensity);
        }
    }
    colours
}

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

fn hue_error_deg(a: Vec3, b: Vec3) -> f64 {
    let (a, b) = (a.as_dvec3(), b.as_dvec3());
    let cos = a.dot(b) / (a.length() * b.length());
    cos.clamp(-1.0, 1.0).acos().to_degrees()
}

struct Stats {
    name: &'static str,
    mean_hue: f64,
    max_hue: f64,
    mean_lum: f64,
    max_lum: f64,
}

fn measure(codec: &dyn ColorCodec, bound: impl Fn(Vec3) -> Vec3) -> Stats {
    let colours = palette();
    let (mut mean_hue, mut max_hue, mut mean_lum, mut max_lum) = (0.0, 0.0_f64, 0.0, 0.0_f64);
    for &c in &colours {
        let d = codec.decode(codec.encode(c));
        let hue = hue_error_deg(c, d);
        let allowed = (f64::from(bound(c).length()) / f64::from(c.length()))
            .min(1.0)
            .asin()
            .to_degrees();
        assert!(
            hue <= allowed + 1e-3,
            "{}: {c} → {d}: hue error {hue}° > bound {allowed}°",
            codec.name()
        );
        let lum = (f64::from(luminance(d)) / f64::from(luminance(c)) - 1.0).abs();
        mean_hue += hue;
        max_hue = max_hue.max(hue);
        mean_lum += lum;
        max_lum = max_lum.max(lum);
    }
    let n = colours.len() as f64;
    Stats {
        name: codec.name(),
        mean_hue: mean_hue / n,
        max_hue,
        mean_lum: mean_lum / n,
        max_lum,
    }
}

fn log_bound(layout: IrradianceLayout, rounding: Rounding) -> impl Fn(Vec3) -> Vec3 {
    move |c: Vec3| {
        Vec3::from_array(std::array::from_fn(|i| {
            layout.channel(i).error_bound(c[i], rounding)
        }))
    }
}

#[test]
fn unequal_split_shifts_hue_more_than_equal_channels() {
    let r11 = |c: Vec3| {
        let f = |v: f32, n: i32| (v * 2f32.powi(-(n + 1))).max(2f32.powi(-15 - n));
        Vec3::new(f(c.x, 6), f(c.y, 6), f(c.z, 5))
    };
    let s998 = measure(
        &LogRgb::ADGI,
        log_bound(IrradianceLayout::ADGI, Rounding::Down),
    );
    let s998n = measure(
        &LogRgb::ADGI_NEAREST,
        log_bound(IrradianceLayout::ADGI, Rounding::Nearest),
    );
    let s101010 = measure(
        &LogRgb::EQUAL_10,
        log_bound(IrradianceLayout::EQUAL_10, Rounding::Down),
    );
    let sr11 = measure(&R11G11B10, r11);
    for s in [&s998, &s998n, &s101010, &sr11] {
        println!(
            "{:<22} hue error mean {:.3}° max {:.3}°   luminance error mean {:.3}% max {:.3}%",
            s.name,
            s.mean_hue,
            s.max_hue,
            100.0 * s.mean_lum,
            100.0 * s.max_lum
        );
    }
    assert!(
        s998.mean_hue > 1.3 * s101010.mean_hue,
        "9/9/8 {} vs 10/10/10 {}",
        s998.mean_hue,
        s101010.mean_hue
    );
    assert!(s998.max_hue > s101010.max_hue);
    assert!(
        s998n.mean_hue < s998.mean_hue,
        "nearest rounding shifts less than round-down"
    );

    // The 8-bit blue channel loses more than the 9-bit red and green (round-down, mean relative).
    let mut rel = [0.0_f64; 3];
    for c in palette() {
        let d = LogRgb::ADGI.decode(LogRgb::ADGI.encode(c));
        for i in 0..3 {
            rel[i] += f64::from((c[i] - d[i]) / c[i]);
        }
    }
    println!("9/9/8 round-down mean relative loss per channel: {rel:?} (sum over palette)");
    assert!(rel[2] > 1.5 * rel[0].max(rel[1]));
}
