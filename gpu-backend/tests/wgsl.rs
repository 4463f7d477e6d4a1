//! WGSL checks that need no GPU: the generated prelude has not drifted from the CPU crates,
//! every module parses and validates with naga, and every WGSL struct that crosses the bus
//! has the size and field offsets of its Rust twin.

use std::path::PathBuf;

use mcg_gpu_backend::{prelude, shaders, types};

use naga::valid::{Capabilities, ValidationFlags, Validator};

fn prelude_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/wgsl/generated/prelude.wgsl")
}

/// The committed prelude equals what `prelude::generate()` emits from the CPU crates today.
/// `MCG_BLESS=1` rewrites the file instead (then rebuild so `include_str!` picks it up).
#[test]
fn generated_prelude_has_not_drifted() {
    let fresh = prelude::generate();
    let path = prelude_path();
    if std::env::var("MCG_BLESS").is_ok_and(|v| v == "1") {
        std::fs::write(&path, &fresh).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == fresh,
        "{} is out of date with the CPU crates' constants; regenerate it with\n    \
         MCG_BLESS=1 cargo test -p mcg-gpu-backend --test wgsl\nand commit it",
        path.display()
    );
    assert_eq!(shaders::PRELUDE, fresh, "rebuild after blessing");
}

fn parse_and_validate(name: &str, source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
    // WebGPU's capabilities only: nothing beyond the defaults.
    Validator::new(ValidationFlags::all(), Capabilities::empty())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
    module
}

const CHECKSUM_DECLARATION: &str =
    "@group(0) @binding(0) var<storage, read_write> hashgrid_checksums: array<atomic<u32>>;\n";

const AGES_DECLARATION: &str =
    "@group(0) @binding(2) var<storage, read_write> hashgrid_ages: array<atomic<u32>>;\n";

const LOGLUV_DECLARATION: &str =
    "@group(0) @binding(3) var<storage, read> codec_logluv_tables: array<f32>;\n";

const TEXEL_DECLARATION: &str =
    "@group(0) @binding(1) var<storage, read_write> codec_texels: array<atomic<u32>>;\n";

#[test]
fn library_modules_validate_alone_and_together() {
    parse_and_validate(
        "prelude",
        &format!("{}{}", shaders::PRELUDE, shaders::COMMON),
    );
    parse_and_validate("vmf", shaders::VMF_MODULE);
    parse_and_validate("color_codec", shaders::COLOR_CODEC_MODULE);
    parse_and_validate(
        "color_codec_texels",
        &format!(
            "{}{}{}",
            shaders::COLOR_CODEC_MODULE,
            shaders::COLOR_CODEC_TEXELS,
            TEXEL_DECLARATION
        ),
    );
    parse_and_validate("hashgrid", shaders::HASHGRID_MODULE);
    parse_and_validate(
        "hashgrid_table",
        &format!(
            "{}{}{}",
            shaders::HASHGRID_MODULE,
            shaders::HASHGRID_TABLE,
            CHECKSUM_DECLARATION
        ),
    );
    parse_and_validate(
        "hashgrid_ages",
        &format!(
            "{}{}{}{}{}",
            shaders::HASHGRID_MODULE,
            shaders::HASHGRID_TABLE,
            shaders::HASHGRID_AGES,
            CHECKSUM_DECLARATION,
            AGES_DECLARATION
        ),
    );
    parse_and_validate(
        "color_codec_logluv",
        &format!(
            "{}{}{}",
            shaders::COLOR_CODEC_MODULE,
            shaders::COLOR_CODEC_LOGLUV,
            LOGLUV_DECLARATION
        ),
    );
    parse_and_validate(
        "vmf_mixture",
        &format!(
            "{}{}const VMF_MIXTURE_K: u32 = 3u;\n",
            shaders::VMF_MODULE,
            shaders::VMF_MIXTURE
        ),
    );
    // All modules in one shader: no name clashes.
    parse_and_validate("all", &all_library_modules());
}

#[test]
fn kernel_modules_validate_with_their_entry_points() {
    for (name, source, entry_points) in shaders::kernels::ALL {
        let module = parse_and_validate(name, source);
        let info = Validator::new(ValidationFlags::all(), Capabilities::empty())
            .validate(&module)
            .unwrap();
        for e in *entry_points {
            let (index, ep) = module
                .entry_points
                .iter()
                .enumerate()
                .find(|(_, ep)| ep.name == *e)
                .unwrap_or_else(|| panic!("{name}: no entry point {e}"));
            // Storage buffers it uses: at most the 4 `GpuContext` asks of the adapter (WebGPU
            // guarantees 8), bound at 0, 1, … (what `GpuContext::dispatch` binds).
            let uses = info.get_entry_point(index);
            let mut bindings = Vec::new();
            let mut storage = 0;
            for (handle, var) in module.global_variables.iter() {
                if uses[handle].is_empty() {
                    continue;
                }
                if let Some(b) = &var.binding {
                    assert_eq!(b.group, 0, "{name}::{e}");
                    bindings.push(b.binding);
                }
                storage += usize::from(matches!(var.space, naga::AddressSpace::Storage { .. }));
            }
            bindings.sort_unstable();
            assert!(storage <= 4, "{name}::{e} uses {storage} storage buffers");
            assert_eq!(
                bindings,
                (0..bindings.len() as u32).collect::<Vec<_>>(),
                "{name}::{e}: bindings not contiguous from 0"
            );
            assert_eq!(ep.stage, naga::ShaderStage::Compute);
            let size = ep.workgroup_size;
            assert_eq!(size, [mcg_gpu_backend::WORKGROUP_SIZE, 1, 1], "{name}::{e}");
            assert!(
                size.iter().product::<u32>() <= 256,
                "WebGPU's default limit"
            );
        }
    }
}

/// Size and member offsets of the WGSL struct `name` in `module`, by naga's layouter.
fn wgsl_layout(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name}"));
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{name} is not a struct");
    };
    // The array stride of the struct (what an `array<T>` of host memory must match).
    let stride = layouter[handle].to_stride();
    assert_eq!(stride, *span, "{name}: span and stride differ");
    (
        stride,
        members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
            .collect(),
    )
}

/// Checks the WGSL struct `name` against a Rust type: the same size (= array stride) and, for
/// every listed `(member, offset)`, the WGSL member of that name at that offset. WGSL members
/// not listed must be padding (`_pad…`).
fn check(module: &naga::Module, name: &str, size: usize, offsets: &[(&str, usize)]) {
    let (wgsl_size, members) = wgsl_layout(module, name);
    assert_eq!(wgsl_size as usize, size, "{name}: WGSL size vs Rust size");
    for (member, offset) in &members {
        match offsets.iter().find(|(n, _)| n == member) {
            Some((_, rust)) => assert_eq!(
                *offset as usize, *rust,
                "{name}.{member}: WGSL offset vs Rust offset"
            ),
            None => assert!(member.starts_with("_pad"), "{name}.{member} not checked"),
        }
    }
    for (rust_name, _) in offsets {
        assert!(
            members.iter().any(|(m, _)| m == rust_name),
            "{name} has no member {rust_name}"
        );
    }
}

/// `(field, offset_of!(T, field))` for fields named like the WGSL members.
macro_rules! fields {
    ($t:ty: $($f:ident),* $(,)?) => {
        &[$((stringify!($f), core::mem::offset_of!($t, $f))),*]
    };
}

/// Every library module and the storage arrays they expect from the includer.
fn all_library_modules() -> String {
    [
        shaders::PRELUDE,
        shaders::COMMON,
        shaders::VMF,
        shaders::VMF_MIXTURE,
        shaders::HASHGRID,
        shaders::HASHGRID_TABLE,
        shaders::HASHGRID_AGES,
        shaders::COLOR_CODEC,
        shaders::COLOR_CODEC_TEXELS,
        shaders::COLOR_CODEC_LOGLUV,
        shaders::MARKOV_GUIDE,
        CHECKSUM_DECLARATION,
        AGES_DECLARATION,
        LOGLUV_DECLARATION,
        TEXEL_DECLARATION,
        "const VMF_MIXTURE_K: u32 = 4u;\n",
    ]
    .concat()
}

#[test]
fn wgsl_structs_match_the_rust_pod_types() {
    use core::mem::{offset_of, size_of};
    use mcg_hashgrid::CellKey;
    use mcg_vmf::{SufficientStats, Vmf};

    let m = parse_and_validate("all", &all_library_modules());

    // Vmf's fields are private: read their offsets from the bytes of a known lobe.
    let lobe = Vmf::new(glam::Vec3::new(0.0, 0.6, 0.8), 7.0).unwrap();
    let words: [f32; 4] = bytemuck::cast(lobe);
    assert_eq!(words, [0.0, 0.6, 0.8, 7.0], "Vmf is mu then kappa");
    check(&m, "Vmf", size_of::<Vmf>(), &[("mu", 0), ("kappa", 12)]);

    let stats_fields = |base: usize| {
        let t = base + offset_of!(SufficientStats, mean_target);
        [
            ("mean_target_x", t),
            ("mean_target_y", t + 4),
            ("mean_target_z", t + 8),
            ("weight_sum", base + offset_of!(SufficientStats, weight_sum)),
            (
                "one_minus_mean_cosine",
                base + offset_of!(SufficientStats, one_minus_mean_cosine),
            ),
            (
                "sample_count",
                base + offset_of!(SufficientStats, sample_count),
            ),
        ]
    };
    check(
        &m,
        "SufficientStats",
        size_of::<SufficientStats>(),
        &stats_fields(0),
    );

    // CellKey's meta word is the little-endian u32 of level, class, extra.
    let key = CellKey::new(glam::IVec3::new(-1, 2, 3), 5, 4).with_extra(0x1234);
    let w: [u32; 4] = bytemuck::cast(key);
    assert_eq!(w, key.words(), "CellKey's bytes are its hash words");
    assert_eq!(offset_of!(CellKey, level), 12);
    check(
        &m,
        "CellKey",
        size_of::<CellKey>(),
        &[("cell", offset_of!(CellKey, cell)), ("meta_word", 12)],
    );

    // GridState: the velocity's three u16 and the u16 count are two u32 words in WGSL.
    {
        use mcg_markov_guide::mcpg::GridState;
        let mut g = GridState::EMPTY;
        g.mean_target = glam::Vec3::new(1.0, 2.0, 3.0);
        g.weight_sum = 4.0;
        g.one_minus_mean_cosine = 5.0;
        g.time = 6.0;
        g.set_velocity(glam::Vec3::new(1.0, -2.0, 0.5));
        let w: [u32; 8] = bytemuck::cast(g);
        let f = |x: f32| x.to_bits();
        assert_eq!(&w[..6], &[f(1.0), f(2.0), f(3.0), f(4.0), f(5.0), f(6.0)]);
        assert_eq!(w[6], 0x3c00 | (0xc000 << 16), "velocity x, y as f16 bits");
        assert_eq!(w[7], 0x3800, "velocity z as f16 bits, count 0");
        let t = offset_of!(GridState, mean_target);
        let mut fields = vec![
            ("mean_target_x", t),
            ("mean_target_y", t + 4),
            ("mean_target_z", t + 8),
            ("velocity_xy", 24),
            ("velocity_z_count", 28),
        ];
        fields.extend_from_slice(fields!(GridState: weight_sum, one_minus_mean_cosine, time));
        check(&m, "GridState", size_of::<GridState>(), &fields);
    }
    // PixelState: the statistics nested, then the score.
    {
        use mcg_markov_guide::mcmm::PixelState;
        check(
            &m,
            "PixelState",
            size_of::<PixelState>(),
            fields!(PixelState: stats, score),
        );
    }
    // VmfMixture for K = 1..=5 against `pack_mixtures`' stride and order.
    for k in 1..=5_usize {
        let module = parse_and_validate(
            "mixture",
            &all_library_modules().replace(
                "const VMF_MIXTURE_K: u32 = 4u;",
                &format!("const VMF_MIXTURE_K: u32 = {k}u;"),
            ),
        );
        check(
            &module,
            "VmfMixture",
            4 * types::mixture_stride_floats(k),
            &[("lobes", 0), ("weights", 16 * k)],
        );
    }
    use types::{
        HashgridLevelParams as L, HashgridTableParams as T, TexelParams, TexelUpdate,
        VmfFitParamsGpu, VmfSample, VmfUpdate,
    };
    check(
        &m,
        "HashgridTable",
        size_of::<T>(),
        fields!(T: capacity, mask, is_mask, max_probes, bucket_hash),
    );
    check(
        &m,
        "HashgridLevels",
        size_of::<L>(),
        fields!(L: tan_half_angle, min_width, levels_per_ln, ln_per_level, max_level),
    );
    check(
        &m,
        "VmfSample",
        size_of::<VmfSample>(),
        fields!(VmfSample: direction, pdf),
    );
    check(
        &m,
        "VmfFitParams",
        size_of::<VmfFitParamsGpu>(),
        fields!(VmfFitParamsGpu: max_count, alpha_min, mean_cosine_update),
    );

    // Kernel-only structs.
    let kernel = |name| {
        let (_, source, _) = shaders::kernels::ALL
            .iter()
            .find(|(n, _, _)| *n == name)
            .unwrap();
        parse_and_validate(name, source)
    };
    use types::{
        HashgridVertexQuery as V, VmfQuery as Q, VmfStatsQuery as SQ, VmfStatsResult as SR,
    };
    check(
        &kernel("vmf"),
        "VmfQuery",
        size_of::<Q>(),
        fields!(Q: direction, uniforms),
    );
    check(
        &kernel("vmf_mixture"),
        "VmfQuery",
        size_of::<Q>(),
        fields!(Q: direction, uniforms),
    );
    let stats_kernels = kernel("vmf_stats");
    check(
        &stats_kernels,
        "VmfStatsQuery",
        size_of::<SQ>(),
        fields!(SQ: shading_point, kappa, other, prior_mean_cosine, prior_weight, prior_decay),
    );
    check(
        &stats_kernels,
        "VmfStatsResult",
        size_of::<SR>(),
        fields!(SR: reconstructed, product, product_scale, mean_cosine, kappa_back),
    );
    check(
        &kernel("vmf_update"),
        "VmfUpdate",
        size_of::<VmfUpdate>(),
        fields!(VmfUpdate: x, weight, y),
    );
    check(
        &kernel("hashgrid_keys"),
        "HashgridVertexQuery",
        size_of::<V>(),
        fields!(V: position, xi_level, normal, u_corner, camera),
    );
    let texels = kernel("color_codec_texels");
    check(
        &texels,
        "TexelUpdate",
        size_of::<TexelUpdate>(),
        fields!(TexelUpdate: sample, texel),
    );
    check(
        &texels,
        "TexelParams",
        size_of::<TexelParams>(),
        fields!(TexelParams: max_count, rounding_mode, rounding_u, word_layout),
    );
    check(
        &kernel("hashgrid_vertices"),
        "HashgridJitterQuery",
        size_of::<types::HashgridJitterQuery>(),
        fields!(types::HashgridJitterQuery: position, u_corner, u_jitter, width),
    );
    check(
        &kernel("hashgrid_ages"),
        "HashgridAgeParams",
        size_of::<types::HashgridAgeParams>(),
        fields!(types::HashgridAgeParams: frame, max_age),
    );
    check(
        &kernel("markov_pixel"),
        "PixelQuery",
        size_of::<types::MarkovPixelQuery>(),
        fields!(types::MarkovPixelQuery: x, prior_mean_cosine, prior_weight, prior_decay),
    );
}

/// A numeric literal in WGSL source: its value, whether it was written as a float, the text.
#[derive(Debug)]
struct Literal {
    value: f64,
    is_float: bool,
    text: String,
    /// The line from the literal on.
    rest: String,
    line: usize,
}

/// The numeric literals of `source` outside `//` comments (their sign is a separate token in
/// WGSL, so values are magnitudes). Identifiers such as `vec3` or `FAST_LN_P0` are skipped.
fn wgsl_literals(source: &str) -> Vec<Literal> {
    let mut out = Vec::new();
    for (line_no, line) in source.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        let b = code.as_bytes();
        let mut i = 0;
        while i < b.len() {
            let c = b[i];
            let starts_ident = c.is_ascii_alphabetic() || c == b'_';
            if starts_ident {
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                continue;
            }
            if !c.is_ascii_digit() {
                i += 1;
                continue;
            }
            let start = i;
            let (value, is_float) = if code[i..].starts_with("0x") || code[i..].starts_with("0X") {
                i += 2;
                let digits = i;
                while i < b.len() && b[i].is_ascii_hexdigit() {
                    i += 1;
                }
                let v = u64::from_str_radix(&code[digits..i], 16).unwrap();
                (v as f64, false)
            } else {
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
                let mut is_float = false;
                if i < b.len() && b[i] == b'.' {
                    is_float = true;
                    i += 1;
                    while i < b.len() && b[i].is_ascii_digit() {
                        i += 1;
                    }
                }
                if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
                    is_float = true;
                    i += 1;
                    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
                        i += 1;
                    }
                    while i < b.len() && b[i].is_ascii_digit() {
                        i += 1;
                    }
                }
                let v: f64 = code[start..i].parse().unwrap();
                (v, is_float)
            };
            let mut end = i;
            if i < b.len() && matches!(b[i], b'u' | b'i' | b'f' | b'h') {
                end += 1;
                i += 1;
            }
            out.push(Literal {
                value,
                is_float: is_float || b[end - 1] == b'f',
                text: code[start..end].to_owned(),
                rest: code[start..].to_owned(),
                line: line_no + 1,
            });
        }
    }
    out
}

/// Every value the generated prelude declares (so every value of the CPU crates' constant
/// tables, and the values derived from them), with its name and whether it is an f32.
fn prelude_values() -> Vec<(String, f64, bool)> {
    let mut out = Vec::new();
    let mut array: Option<String> = None;
    for line in shaders::PRELUDE.lines() {
        if let Some(name) = &array {
            if line.starts_with(')') {
                array = None;
                continue;
            }
            for (i, item) in line.split(',').filter(|t| !t.trim().is_empty()).enumerate() {
                let v: f64 = item.trim().parse().unwrap();
                out.push((format!("{name}[{i}…]"), v.abs(), true));
            }
            continue;
        }
        let Some(decl) = line.strip_prefix("const ") else {
            continue;
        };
        let (name, rest) = decl.split_once(": ").unwrap();
        if rest.starts_with("array<") {
            array = Some(name.to_owned());
            continue;
        }
        let (ty, literal) = rest.split_once(" = ").unwrap();
        let literal = literal.trim_end_matches(';').trim_end_matches('u');
        out.push((
            name.to_owned(),
            literal.parse::<f64>().unwrap().abs(),
            ty == "f32",
        ));
    }
    out
}

/// The table constants that `literal` would be a hand-typed copy of.
///
/// False positives are the design problem: WGSL code is full of small integers (bit widths,
/// shifts, the IEEE-754 fields 23 and 127, loop bounds, `2u * axis`) and of 0.5, 1 and 2 as
/// plain arithmetic, and some table constants share those values (`HASHGRID_CHECKSUM_WORD` = 2,
/// `IRRADIANCE_R_BITS` = 9). So an integer literal counts only above 256, and a float literal
/// counts unless it is 0, ½, 1, 2 or 4 (`4.0 * t`, quarter turns). Table constants with those
/// values (e.g. `VMF_SERIES_LIMIT` = 0.5, `HASHGRID_LEVEL_SHIFT` = 0) are beyond this check
/// and kept honest by review: the prelude names them.
fn duplicates_of<'a>(literal: &Literal, table: &'a [(String, f64, bool)]) -> Vec<&'a str> {
    let v = literal.value;
    let trivial = if literal.is_float {
        [0.0, 0.5, 1.0, 2.0, 4.0].contains(&v)
    } else {
        v <= 256.0
    };
    if trivial {
        return Vec::new();
    }
    table
        .iter()
        .filter(|(_, t, t_is_f32)| {
            // An f32 literal equals a table f32 when both round to the same f32.
            let same = if literal.is_float || *t_is_f32 {
                v as f32 == *t as f32
            } else {
                v == *t
            };
            // Integers typed as floats (1023.0) count only above 256 too.
            same && (*t_is_f32 || *t > 256.0)
        })
        .map(|(n, _, _)| n.as_str())
        .collect()
}

/// Literals reviewed as not copies: fixed layouts of hardware formats and colour-science
/// coefficients whose values coincide with a table constant of another meaning. (file, the
/// literal as typed with what follows it on the line, why.)
const NOT_COPIES: &[(&str, &str, &str)] = &[
    (
        "color_codec.wgsl",
        "511u",
        "RGB9E5's 9-bit mantissa (VK_FORMAT_E5B9G9R9_UFLOAT_PACK32), not the irradiance field",
    ),
    (
        "color_codec.wgsl",
        "0x1ffu",
        "RGB9E5's 9-bit mantissa mask, not the irradiance field",
    ),
    (
        "markov_guide.wgsl",
        "0x3ffu",
        "IEEE-754 binary16's 10-bit mantissa mask, not gamma-5's code range",
    ),
    (
        "color_codec_logluv.wgsl",
        "15.0 *",
        "CIE 1976 u′v′: S = X + 15Y + 3Z, not a log codec's γ = 15",
    ),
    (
        "color_codec_logluv.wgsl",
        "9.0 *",
        "CIE 1976 v′ = 9Y/S, not vMF's κ switch point 9",
    ),
];

fn hand_written_wgsl() -> Vec<(PathBuf, String)> {
    fn walk(dir: &std::path::Path, out: &mut Vec<(PathBuf, String)>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                if path.file_name().is_some_and(|n| n != "generated") {
                    walk(&path, out);
                }
            } else if path.extension().is_some_and(|e| e == "wgsl") {
                let text = std::fs::read_to_string(&path).unwrap();
                out.push((path, text));
            }
        }
    }
    let mut out = Vec::new();
    walk(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/wgsl"),
        &mut out,
    );
    out.sort();
    out
}

/// No value of the CPU crates' constant tables (as the generated prelude declares them) is
/// typed again in a hand-written WGSL file (`src/wgsl/**`, not `generated/`): polynomial
/// coefficients, switch points, primes, masks and scales must come from the prelude by name.
/// See [`duplicates_of`] for what counts as a copy and [`NOT_COPIES`] for the reviewed
/// coincidences. The check itself is checked: re-typing
/// the golden-ratio step, a fast-`ln` coefficient, √½'s bits, a hash prime, a κ switch point
/// or gamma-5's 1023 is caught.
#[test]
fn no_table_constant_is_typed_again_in_wgsl() {
    let table = prelude_values();
    assert!(table.len() > 100, "{} prelude constants", table.len());
    let planted = "let a = u + f32(k) * 0.618034; let b = -2.4999994e-1 * t;\n\
                   let c = bits - 0x3f3504f3u; let d = w.y * 2654435761u;\n\
                   if kappa > 17.0 { return c * 1023.0; } // 805459861u in a comment is fine\n\
                   let fine = vec3<f32>(2.0 * x, 0.5, 127u + 23u) + P0 + x2;";
    let caught: Vec<String> = wgsl_literals(planted)
        .iter()
        .filter(|l| !duplicates_of(l, &table).is_empty())
        .map(|l| l.text.clone())
        .collect();
    assert_eq!(
        caught,
        [
            "0.618034",
            "2.4999994e-1",
            "0x3f3504f3u",
            "2654435761u",
            "17.0",
            "1023.0"
        ]
    );
    let mut found = Vec::new();
    let files = hand_written_wgsl();
    assert!(files.len() >= 14, "{} WGSL files", files.len());
    for (path, text) in &files {
        for literal in wgsl_literals(text) {
            let names = duplicates_of(&literal, &table);
            let file = path.file_name().unwrap().to_string_lossy();
            let reviewed = NOT_COPIES.iter().any(|(f, text, _)| {
                *f == file && text.starts_with(&literal.text) && literal.rest.starts_with(text)
            });
            if !names.is_empty() && !reviewed {
                found.push(format!(
                    "{file}:{}: `{}` is {}",
                    literal.line,
                    literal.text,
                    names.join(" / ")
                ));
            }
        }
    }
    assert!(
        found.is_empty(),
        "table constants typed again in WGSL (use the prelude's names):\n{}",
        found.join("\n")
    );
}
