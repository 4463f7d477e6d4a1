//! The shader library without a GPU: the generated constants have not drifted from the CPU
//! crates; every module composes through naga_oil and through the plain-WGSL composer and
//! validates with naga; every module-scope name carries an mcg prefix; errors in a user's
//! shader point at the user's own line; every WGSL struct that crosses the bus has the size
//! and field offsets of its Rust twin; no table constant is typed twice.

use std::collections::HashMap;
use std::path::PathBuf;

use mcg_gpu_backend::shaders::{self, Module, constants, defs, kernels};
use mcg_gpu_backend::types;
use naga::valid::{Capabilities, ValidationFlags, Validator};
use naga_oil::compose::{Composer, NagaModuleDescriptor, ShaderDefValue};

fn constants_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/shaders/constants.wgsl")
}

/// The committed `mcg::constants` equals what `constants::generate()` emits from the CPU crates
/// today. `MCG_BLESS=1` rewrites the file instead (then rebuild so `include_str!` picks it up).
#[test]
fn generated_constants_have_not_drifted() {
    let fresh = constants::generate();
    let path = constants_path();
    if std::env::var("MCG_BLESS").is_ok_and(|v| v == "1") {
        std::fs::write(&path, &fresh).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == fresh,
        "{} is out of date with the CPU crates' constants; regenerate it with\n    \
         MCG_BLESS=1 cargo test -p mcg-gpu-backend --test modules\nand commit it",
        path.display()
    );
    assert_eq!(Module::Constants.source(), fresh, "rebuild after blessing");
}

fn validate(name: &str, module: &naga::Module, source: &str) -> naga::valid::ModuleInfo {
    // WebGPU's capabilities only: nothing beyond the defaults.
    Validator::new(ValidationFlags::all(), Capabilities::empty())
        .validate(module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)))
}

fn parse_and_validate(name: &str, source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
    validate(name, &module, source);
    module
}

/// Group 0, bindings 1, 2 and 3 for the three storage arrays of the library; the MCPG guide's
/// group is 1, the MCMM guide's 2, ADGI's probe cache 3 (its texel words are the library's
/// `mcg_codec_texels`).
const DEFS: &[(&str, u32)] = &[
    (defs::MCPG_GROUP, 1),
    (defs::ADGI_GROUP, 3),
    (defs::HASHGRID_GROUP, 0),
    (defs::HASHGRID_BINDING, 1),
    (defs::CODEC_TEXELS_GROUP, 0),
    (defs::CODEC_TEXELS_BINDING, 2),
    (defs::CODEC_LOGLUV_GROUP, 0),
    (defs::CODEC_LOGLUV_BINDING, 3),
    // The MCMM guide's group (bindings 0-2 of group 2).
    (defs::MCMM_GROUP, 2),
];

fn naga_oil_defs(defs: &[(&str, u32)]) -> HashMap<String, ShaderDefValue> {
    defs.iter()
        .map(|&(n, v)| (n.to_string(), ShaderDefValue::UInt(v)))
        .collect()
}

fn composer() -> Composer {
    let mut composer = Composer::default();
    shaders::add_to_composer(&mut composer).unwrap();
    // Twice is harmless.
    shaders::add_to_composer(&mut composer).unwrap();
    composer
}

/// Every module-scope name of a module as a user shader sees it: a shader that imports the
/// whole module and calls nothing.
fn whole_module_shader(module: Module) -> String {
    format!(
        "#import {}\n@compute @workgroup_size(1)\nfn user_main() {{}}\n",
        module.import_path()
    )
}

#[test]
fn every_module_composes_through_naga_oil_and_validates() {
    let mut composer = composer();
    for module in Module::ALL {
        let source = whole_module_shader(module);
        let composed = composer
            .make_naga_module(NagaModuleDescriptor {
                source: &source,
                file_path: "user.wgsl",
                shader_defs: naga_oil_defs(DEFS),
                ..Default::default()
            })
            .unwrap_or_else(|e| {
                panic!("{}: {}", module.import_path(), e.emit_to_string(&composer))
            });
        validate(module.import_path(), &composed, &source);
    }
}

#[test]
fn every_module_composes_as_plain_wgsl_and_validates() {
    for module in Module::ALL {
        let plain = shaders::wgsl(&[module], DEFS).unwrap();
        parse_and_validate(module.import_path(), &plain);
        // Each dependency exactly once, in an order where it comes after what it imports.
        for dep in module.dependencies() {
            let position = |m: Module| Module::ALL.iter().position(|&a| a == m);
            assert!(position(dep) < position(module), "{dep:?} after {module:?}");
            let marker = format!("// ---- {} ", dep.import_path());
            assert_eq!(plain.matches(&marker).count(), 1, "{module:?}: {dep:?}");
        }
    }
    let all = shaders::wgsl(&Module::ALL, DEFS).unwrap();
    parse_and_validate("all modules", &all);
    // Constants come only with the modules that use them.
    let vmf = shaders::wgsl(&[Module::Vmf], &[]).unwrap();
    assert!(!vmf.contains("HASHGRID_") && !vmf.contains("CODEC_"));
    assert!(vmf.contains("const VMF_KAPPA_MAX"));
}

#[test]
fn missing_shader_defs_are_named() {
    let err = shaders::wgsl(&[Module::HashgridTable], &[]).unwrap_err();
    assert!(err.to_string().contains("MCG_HASHGRID_GROUP"), "{err}");
    assert!(err.to_string().contains("mcg/hashgrid_table.wgsl"), "{err}");
}

/// Module-scope names of `module` defined by the module itself (not its imports).
fn own_names(module: Module) -> Vec<String> {
    let source = shaders::wgsl(&[module], DEFS).unwrap();
    let marker = format!("// ---- {} ", module.import_path());
    let own = &source[source.find(&marker).unwrap()..];
    let parsed = naga::front::wgsl::parse_str(&source).unwrap();
    let mut names = Vec::new();
    let in_own = |name: &str| {
        own.contains(&format!("fn {name}("))
            || own.contains(&format!("struct {name} "))
            || own.contains(&format!("const {name}:"))
            || own.contains(&format!("> {name}:"))
    };
    for (_, f) in parsed.functions.iter() {
        names.extend(f.name.clone());
    }
    for (_, c) in parsed.constants.iter() {
        names.extend(c.name.clone());
    }
    for (_, ty) in parsed.types.iter() {
        if matches!(ty.inner, naga::TypeInner::Struct { .. }) {
            names.extend(ty.name.clone());
        }
    }
    for (_, g) in parsed.global_variables.iter() {
        names.extend(g.name.clone());
    }
    names.retain(|n| in_own(n));
    names
}

/// The library's prefixes, in the case of each kind of name: `vmf_pdf`, `Vmf`,
/// `VMF_KAPPA_MAX`, `mcg_rounded`, `McgDirectionSample`, `MCG_PI`.
fn has_mcg_prefix(name: &str) -> bool {
    [
        "mcg", "vmf", "hashgrid", "codec", "markov", "mcpg", "mcmm", "adgi",
    ]
    .iter()
    .any(|p| {
        let camel = format!("{}{}", p[..1].to_uppercase(), &p[1..]);
        name.starts_with(&format!("{p}_"))
            || name.starts_with(&format!("{}_", p.to_uppercase()))
            || name.starts_with(&camel)
    })
}

#[test]
fn every_module_scope_name_carries_an_mcg_prefix() {
    let mut unprefixed = Vec::new();
    let mut total = 0;
    for module in Module::ALL {
        let names = own_names(module);
        assert!(!names.is_empty(), "{module:?}");
        total += names.len();
        unprefixed.extend(
            names
                .into_iter()
                .filter(|n| !has_mcg_prefix(n))
                .map(|n| format!("{}: {n}", module.import_path())),
        );
    }
    assert!(total > 300, "{total} names scanned");
    assert!(
        unprefixed.is_empty(),
        "unprefixed names:\n{}",
        unprefixed.join("\n")
    );
    // The scan itself is checked.
    assert!(!has_mcg_prefix("GridState") && !has_mcg_prefix("DISTANCE_BETA"));
    assert!(has_mcg_prefix("Vmf") && has_mcg_prefix("HASHGRID_FULL") && has_mcg_prefix("mcg_pi"));
}

/// A user's typo is reported in the user's file at the user's line, by both composers.
#[test]
fn errors_point_at_the_users_own_line() {
    let user = "#import mcg::vmf::{Vmf, vmf_pdf}\n\n@group(0) @binding(0) var<storage, read_write> out: array<f32>;\n\n@compute @workgroup_size(64)\nfn main(@builtin(global_invocation_id) id: vec3<u32>) {\n    out[id.x] = vmf_pdf(Vmf(vec3<f32>(0.0, 0.0, 1.0), 10.0), undefined_name);\n}\n";
    let mut composer = composer();
    let err = composer
        .make_naga_module(NagaModuleDescriptor {
            source: user,
            file_path: "my_renderer/guide.wgsl",
            ..Default::default()
        })
        .unwrap_err();
    let report = err.emit_to_string(&composer);
    assert!(report.contains("my_renderer/guide.wgsl:7"), "{report}");
    let plain = shaders::compose(user, &[]).unwrap();
    let parse = naga::front::wgsl::parse_str(&plain).unwrap_err();
    let location = parse.location(&plain).unwrap();
    assert_eq!(location.line_number, 7, "{}", parse.emit_to_string(&plain));
}

#[test]
fn kernel_modules_validate_with_their_entry_points() {
    let mut composer = composer();
    for (name, source, entry_points) in kernels::ALL {
        // Through naga_oil, as a user's shader would be …
        composer
            .make_naga_module(NagaModuleDescriptor {
                source,
                file_path: name,
                shader_defs: naga_oil_defs(kernels::KERNEL_DEFS),
                ..Default::default()
            })
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&composer)));
        // … and as the plain WGSL the host side runs.
        let plain = kernels::plain(source);
        let module = parse_and_validate(name, &plain);
        let info = validate(name, &module, &plain);
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
/// not listed must be padding (`pad…`, `reserved`).
fn check(module: &naga::Module, name: &str, size: usize, offsets: &[(&str, usize)]) {
    let (wgsl_size, members) = wgsl_layout(module, name);
    assert_eq!(wgsl_size as usize, size, "{name}: WGSL size vs Rust size");
    for (member, offset) in &members {
        match offsets.iter().find(|(n, _)| n == member) {
            Some((_, rust)) => assert_eq!(
                *offset as usize, *rust,
                "{name}.{member}: WGSL offset vs Rust offset"
            ),
            None => assert!(
                member.starts_with("pad") || member == "reserved",
                "{name}.{member} not checked"
            ),
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
    shaders::wgsl(&Module::ALL, DEFS).unwrap()
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
        "VmfSufficientStats",
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
        "HashgridCellKey",
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
        check(&m, "MarkovGridState", size_of::<GridState>(), &fields);
    }
    // The MCPG guide's parameters (a uniform: its layout rules put every struct member at a
    // multiple of 16, which the Rust field order keeps).
    {
        use mcg_gpu_backend::guides::mcpg::McpgGpuParams;
        check(
            &m,
            "McpgParams",
            size_of::<McpgGpuParams>(),
            fields!(McpgGpuParams: candidates, adaptive_probability, bsdf_probability,
                prior_scale, prior_min_weight, static_normal_threshold, discard_rule,
                discard_ratio, fit, hemisphere, environment_distance, static_width, age_tracking,
                camera, max_state_age, levels, adaptive_table, static_table, cache_table,
                cache_enabled, cache_accumulation, cache_coarser_levels, cache_level_bias,
                cache_max_age, cache_max_weight, adaptive_states, static_states, adaptive_guards,
                static_guards, cache_cells, cache_sums, confidence_inverse, cache_add_scale, widths),
        );
    }
    // ADGI's probe cache: the parameters (a uniform) and the structs its steps exchange.
    {
        use mcg_gpu_backend::guides::adgi::{
            AdgiGpuParams as P, GpuClipVolume, GpuClipVolumes, GpuRaySample,
        };
        check(
            &m,
            "AdgiParams",
            size_of::<P>(),
            fields!(P: origin, cell_diagonal, spacing, min_spacing, counts, probe_count,
                irradiance_side, irradiance_interior, visibility_side, visibility_interior,
                visibility_offset, max_count, rounding, rays_per_probe, max_distance,
                irradiance_max_value, irradiance_power, distance_power, radiance_content,
                normal_bias, view_bias, wrap_shading, visibility, chebyshev_floor,
                crush_threshold, min_weight, min_trilinear, sqrt_blend, shell_count, pad_a),
        );
        check(
            &m,
            "AdgiRaySample",
            size_of::<GpuRaySample>(),
            fields!(GpuRaySample: direction, distance, radiance, probe),
        );
        check(
            &m,
            "AdgiClipVolume",
            size_of::<GpuClipVolume>(),
            fields!(GpuClipVolume: planes, min_corner, max_corner),
        );
        check(
            &m,
            "AdgiClipVolumes",
            size_of::<GpuClipVolumes>(),
            fields!(GpuClipVolumes: inner, outer),
        );
        use mcg_gpu_backend::guides::adgi::{GpuIrradianceQuery, GpuProbeCache, GpuStepParams};
        let steps = parse_and_validate(
            "adgi steps",
            &shaders::compose(kernels::ADGI_STEPS, &GpuProbeCache::shader_defs(0)).unwrap(),
        );
        check(
            &steps,
            "AdgiStep",
            size_of::<GpuStepParams>(),
            fields!(GpuStepParams: count, max_count, cap, pad_a),
        );
        check(
            &steps,
            "AdgiQuery",
            size_of::<GpuIrradianceQuery>(),
            fields!(GpuIrradianceQuery: position, normal, to_viewer),
        );
        use mcg_gpu_backend::guides::adgi::GpuPilotStep;
        check(
            &steps,
            "AdgiPilotStep",
            size_of::<GpuPilotStep>(),
            fields!(GpuPilotStep: voxel_diagonal, radiance_range, decay, detect),
        );
        // The probe chains' module, kernels and the triggers' smoothing.
        use mcg_gpu_backend::guides::adgi::{
            GpuChainParams as C, GpuChainState, GpuGuideQuery, GpuProbeSample, GpuSmoothingPass,
        };
        check(
            &m,
            "AdgiChainState",
            size_of::<GpuChainState>(),
            fields!(GpuChainState: position, z, phi, target_value, accepted, restarted),
        );
        let chains = parse_and_validate(
            "adgi chains",
            &shaders::compose(kernels::ADGI_CHAINS, &[]).unwrap(),
        );
        check(
            &chains,
            "AdgiChainParams",
            size_of::<C>(),
            fields!(C: origin, probe_count, spacing, pad_d, counts, pad_e, lo, block, extent,
                chain_count, position_step, direction_step, cell_counts, dedup, iterations,
                burn_in, seed, capacity, alpha, exponent_cap, has_feedback, field, count, pad_a,
                pad_b, pad_c),
        );
        check(
            &m,
            "AdgiProbeSample",
            size_of::<GpuProbeSample>(),
            fields!(GpuProbeSample: position, cell, direction, guiding_value, probe, octant,
                chain, step),
        );
        check(
            &chains,
            "AdgiGuideQuery",
            size_of::<GpuGuideQuery>(),
            fields!(GpuGuideQuery: position, direction),
        );
        let smoothing = parse_and_validate(
            "adgi smoothing",
            &shaders::compose(kernels::ADGI_SMOOTHING, &GpuProbeCache::shader_defs(0)).unwrap(),
        );
        check(
            &smoothing,
            "AdgiSmoothingPass",
            size_of::<GpuSmoothingPass>(),
            fields!(GpuSmoothingPass: axis, radius, directional, pad_a),
        );
        // The feedback ĝ and the heuristics' composition on the cache's group.
        parse_and_validate(
            "adgi feedback",
            &shaders::compose(kernels::ADGI_FEEDBACK, &GpuProbeCache::shader_defs(0)).unwrap(),
        );
        let compose = parse_and_validate(
            "adgi compose",
            &shaders::compose(kernels::ADGI_COMPOSE, &GpuProbeCache::shader_defs(0)).unwrap(),
        );
        use mcg_gpu_backend::guides::adgi::GpuComposeParams;
        check(
            &compose,
            "AdgiCompose",
            size_of::<GpuComposeParams>(),
            fields!(GpuComposeParams: camera, camera_threshold, lighting_weight, pad_a, pad_b,
                pad_c),
        );
        // The float-texel variant (the benches' baseline) composes and validates too.
        let mut float_defs = DEFS.to_vec();
        float_defs.push((defs::ADGI_FLOAT_TEXELS, 1));
        let float = shaders::wgsl(&[Module::Adgi], &float_defs).unwrap();
        assert!(float.contains("adgi_float_irradiance"));
        parse_and_validate("adgi float texels", &float);
    }
    // PixelState: the statistics nested, then the score.
    {
        use mcg_markov_guide::mcmm::PixelState;
        check(
            &m,
            "MarkovPixelState",
            size_of::<PixelState>(),
            fields!(PixelState: stats, score),
        );
    }
    // VmfMixture for K = 1..=5 against `pack_mixtures`' stride and order.
    for k in 1..=5_usize {
        let module = parse_and_validate(
            "mixture",
            &shaders::wgsl(
                &[Module::VmfMixture],
                &[(defs::VMF_MIXTURE_K, u32::try_from(k).unwrap())],
            )
            .unwrap(),
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
        fields!(T: capacity, mask, is_mask, max_probes, bucket_hash, checksum_offset, age_offset),
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
    {
        use mcg_gpu_backend::guides::mcmm::GpuMcmmParams as P;
        check(
            &m,
            "McmmParams",
            size_of::<P>(),
            fields!(P: fit, hemisphere_probability, prior_mean_cosine, prior_weight, prior_decay, prior_kind, prior_radius, neighbour_candidates, window_half_width, score_density, width, height),
        );
    }

    // Kernel-only structs.
    let kernel = |name| {
        let (_, source, _) = shaders::kernels::ALL
            .iter()
            .find(|(n, _, _)| *n == name)
            .unwrap();
        parse_and_validate(name, &kernels::plain(source))
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
/// WGSL, so values are magnitudes). Identifiers such as `vec3` or `CODEC_FAST_LN_P0` are skipped.
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
    for line in Module::Constants.source().lines() {
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
/// `CODEC_IRRADIANCE_R_BITS` = 9). So an integer literal counts only above 256, and a float literal
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
        "0xffffffffu, bits",
        "the all-ones mask of a 32-bit field, not the hash table's HASHGRID_NO_SLOT",
    ),
    (
        "vmf.wgsl",
        "0xffffffffu)",
        "u32::MAX, the saturated sample count, not the hash table's HASHGRID_NO_SLOT",
    ),
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
        "markov.wgsl",
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
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "wgsl")
                && path.file_name().is_some_and(|n| n != "constants.wgsl")
            {
                let text = std::fs::read_to_string(&path).unwrap();
                out.push((path, text));
            }
        }
    }
    let mut out = Vec::new();
    for dir in ["src/shaders", "src/guides"] {
        walk(
            &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(dir),
            &mut out,
        );
    }
    out.sort();
    out
}

/// No value of the CPU crates' constant tables (as the generated prelude declares them) is
/// typed again in a hand-written WGSL file (`src/shaders/**`, not `constants.wgsl`): polynomial
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
