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
    // All modules in one shader: no name clashes.
    let all = [
        shaders::PRELUDE,
        shaders::COMMON,
        shaders::VMF,
        shaders::HASHGRID,
        shaders::HASHGRID_TABLE,
        shaders::COLOR_CODEC,
        shaders::COLOR_CODEC_TEXELS,
        shaders::MARKOV_GUIDE,
        CHECKSUM_DECLARATION,
        TEXEL_DECLARATION,
    ]
    .concat();
    parse_and_validate("all", &all);
}

#[test]
fn kernel_modules_validate_with_their_entry_points() {
    for (name, source, entry_points) in shaders::kernels::ALL {
        let module = parse_and_validate(name, source);
        for e in *entry_points {
            let ep = module
                .entry_points
                .iter()
                .find(|ep| ep.name == *e)
                .unwrap_or_else(|| panic!("{name}: no entry point {e}"));
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

fn check(module: &naga::Module, name: &str, size: usize, offsets: &[(&str, usize)]) {
    let (wgsl_size, members) = wgsl_layout(module, name);
    assert_eq!(wgsl_size as usize, size, "{name}: WGSL size vs Rust size");
    assert_eq!(members.len(), offsets.len(), "{name}: member count");
    for ((wgsl_name, wgsl_offset), (rust_name, rust_offset)) in members.iter().zip(offsets) {
        assert_eq!(wgsl_name, rust_name, "{name}: member order");
        assert_eq!(
            *wgsl_offset as usize, *rust_offset,
            "{name}.{wgsl_name}: WGSL offset vs Rust offset"
        );
    }
}

#[test]
fn wgsl_structs_match_the_rust_pod_types() {
    use core::mem::{offset_of, size_of};
    use mcg_hashgrid::CellKey;
    use mcg_vmf::{SufficientStats, Vmf};

    let all = [
        shaders::PRELUDE,
        shaders::COMMON,
        shaders::VMF,
        shaders::HASHGRID,
        shaders::HASHGRID_TABLE,
        shaders::COLOR_CODEC,
        shaders::COLOR_CODEC_TEXELS,
        shaders::MARKOV_GUIDE,
        CHECKSUM_DECLARATION,
        TEXEL_DECLARATION,
    ]
    .concat();
    let m = parse_and_validate("all", &all);

    // Vmf's fields are private: read their offsets from the bytes of a known lobe.
    let lobe = Vmf::new(glam::Vec3::new(0.0, 0.6, 0.8), 7.0).unwrap();
    let words: [f32; 4] = bytemuck::cast(lobe);
    assert_eq!(words, [0.0, 0.6, 0.8, 7.0], "Vmf is mu then kappa");
    check(&m, "Vmf", size_of::<Vmf>(), &[("mu", 0), ("kappa", 12)]);

    check(
        &m,
        "SufficientStats",
        size_of::<SufficientStats>(),
        &[
            ("mean_target_x", offset_of!(SufficientStats, mean_target)),
            (
                "mean_target_y",
                offset_of!(SufficientStats, mean_target) + 4,
            ),
            (
                "mean_target_z",
                offset_of!(SufficientStats, mean_target) + 8,
            ),
            ("weight_sum", offset_of!(SufficientStats, weight_sum)),
            (
                "one_minus_mean_cosine",
                offset_of!(SufficientStats, one_minus_mean_cosine),
            ),
            ("sample_count", offset_of!(SufficientStats, sample_count)),
        ],
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
        check(
            &m,
            "GridState",
            size_of::<GridState>(),
            &[
                ("mean_target_x", offset_of!(GridState, mean_target)),
                ("mean_target_y", offset_of!(GridState, mean_target) + 4),
                ("mean_target_z", offset_of!(GridState, mean_target) + 8),
                ("weight_sum", offset_of!(GridState, weight_sum)),
                (
                    "one_minus_mean_cosine",
                    offset_of!(GridState, one_minus_mean_cosine),
                ),
                ("time", offset_of!(GridState, time)),
                ("velocity_xy", 24),
                ("velocity_z_count", 28),
            ],
        );
    }
    check(
        &m,
        "HashgridTable",
        size_of::<types::HashgridTableParams>(),
        &[
            ("capacity", 0),
            ("mask", 4),
            ("is_mask", 8),
            ("max_probes", 12),
            ("bucket_hash", 16),
            ("_pad0", 20),
            ("_pad1", 24),
            ("_pad2", 28),
        ],
    );
    check(
        &m,
        "HashgridLevels",
        size_of::<types::HashgridLevelParams>(),
        &[
            (
                "tan_half_angle",
                offset_of!(types::HashgridLevelParams, tan_half_angle),
            ),
            (
                "min_width",
                offset_of!(types::HashgridLevelParams, min_width),
            ),
            (
                "levels_per_ln",
                offset_of!(types::HashgridLevelParams, levels_per_ln),
            ),
            (
                "ln_per_level",
                offset_of!(types::HashgridLevelParams, ln_per_level),
            ),
            (
                "max_level",
                offset_of!(types::HashgridLevelParams, max_level),
            ),
            ("_pad0", 20),
            ("_pad1", 24),
            ("_pad2", 28),
        ],
    );
    check(
        &m,
        "VmfSample",
        size_of::<types::VmfSample>(),
        &[
            ("direction", offset_of!(types::VmfSample, direction)),
            ("pdf", offset_of!(types::VmfSample, pdf)),
        ],
    );

    let vmf_kernels = parse_and_validate("vmf kernels", shaders::kernels::VMF);
    check(
        &vmf_kernels,
        "VmfQuery",
        size_of::<types::VmfQuery>(),
        &[
            ("direction", offset_of!(types::VmfQuery, direction)),
            ("uniforms", offset_of!(types::VmfQuery, uniforms)),
        ],
    );
    let stats_kernels = parse_and_validate("vmf stats kernels", shaders::kernels::VMF_STATS);
    use types::{VmfStatsQuery as Q, VmfStatsResult as R};
    check(
        &stats_kernels,
        "VmfStatsQuery",
        size_of::<Q>(),
        &[
            ("shading_point", offset_of!(Q, shading_point)),
            ("kappa", offset_of!(Q, kappa)),
            ("other", offset_of!(Q, other)),
            ("prior_mean_cosine", offset_of!(Q, prior_mean_cosine)),
            ("prior_weight", offset_of!(Q, prior_weight)),
            ("prior_decay", offset_of!(Q, prior_decay)),
        ],
    );
    check(
        &stats_kernels,
        "VmfStatsResult",
        size_of::<R>(),
        &[
            ("reconstructed", offset_of!(R, reconstructed)),
            ("product", offset_of!(R, product)),
            ("product_scale", offset_of!(R, product_scale)),
            ("mean_cosine", offset_of!(R, mean_cosine)),
            ("kappa_back", offset_of!(R, kappa_back)),
        ],
    );
    let key_kernels = parse_and_validate("hashgrid key kernels", shaders::kernels::HASHGRID_KEYS);
    use types::HashgridVertexQuery as V;
    check(
        &key_kernels,
        "HashgridVertexQuery",
        size_of::<V>(),
        &[
            ("position", offset_of!(V, position)),
            ("xi_level", offset_of!(V, xi_level)),
            ("normal", offset_of!(V, normal)),
            ("u_corner", offset_of!(V, u_corner)),
            ("camera", offset_of!(V, camera)),
        ],
    );
}
