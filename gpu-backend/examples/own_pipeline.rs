//! Import mcg's WGSL modules into your own compute shader with naga_oil, and run it in a
//! pipeline built with plain wgpu calls.
//!
//! The shader below is yours: it `#import`s what it needs from `mcg::vmf` and `mcg::hashgrid`,
//! declares its own bindings, and calls `vmf_sample_with_pdf` and `hashgrid_checksum` like any
//! WGSL function. naga_oil composes it (errors name your file and line); the host side uses
//! only wgpu (the device comes from `GpuContext` for brevity; any `wgpu::Device` works). The
//! results are checked against the CPU crates.
//!
//! Run: `cargo run --release -p mcg-gpu-backend --example own_pipeline`

use mcg_gpu_backend::mcg_hashgrid::{CellKey, checksum, glam::IVec3};
use mcg_gpu_backend::mcg_vmf::{
    Vmf,
    glam::{Vec2, Vec3},
};
use mcg_gpu_backend::naga_oil::compose::{Composer, NagaModuleDescriptor};
use mcg_gpu_backend::wgpu::{self, util::DeviceExt};
use mcg_gpu_backend::{GpuContext, shaders};

const MY_CODE: &str = r#"
#import mcg::vmf::{Vmf, vmf_sample_with_pdf}
#import mcg::hashgrid::{hashgrid_cell_key, hashgrid_normal_class, hashgrid_checksum}

struct Out {
    direction: vec3<f32>,
    pdf: f32,
    key_checksum: u32,
}

@group(0) @binding(0) var<storage, read> uniforms: array<vec2<f32>>;
@group(0) @binding(1) var<storage, read_write> out: array<Out>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out) {
        return;
    }
    // A lobe around +z with κ = 40, sampled with the caller's uniforms.
    let s = vmf_sample_with_pdf(Vmf(vec3<f32>(0.0, 0.0, 1.0), 40.0), uniforms[i]);
    // The hash-grid cell the sample points into, on a grid of width 0.1 one unit away.
    let key = hashgrid_cell_key(vec3<i32>(floor(s.direction / 0.1)), 0u, hashgrid_normal_class(s.direction));
    out[i] = Out(s.direction, s.pdf, hashgrid_checksum(key));
}
"#;

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Out {
    direction: [f32; 3],
    pdf: f32,
    key_checksum: u32,
    _pad: [u32; 3], // WGSL rounds the struct up to its 16-byte alignment: 32 bytes.
}

fn main() {
    let ctx = match GpuContext::new() {
        Ok(ctx) => ctx,
        Err(e) => {
            println!("no GPU to run on: {e}");
            return;
        }
    };
    println!("adapter: {}", ctx.adapter_info().name);
    let (device, queue) = (ctx.device(), ctx.queue());

    // 1. Compose with naga_oil: register mcg's modules, then build your shader.
    let pipeline = compose_pipeline(device);

    // 2. Buffers and dispatch, plain wgpu.
    let n = 256_usize;
    let uniforms: Vec<[f32; 2]> = (0..n)
        .map(|i| {
            [
                (i as f32 + 0.5) / n as f32,
                ((i * 37) % n) as f32 / n as f32,
            ]
        })
        .collect();
    let results = dispatch(device, queue, &pipeline, &uniforms);

    // 3. The CPU crates give the same answers.
    let worst = check_against_cpu(&uniforms, &results);
    println!("{n} samples: largest |ω_gpu − ω_cpu| = {worst:.2e}; every checksum equals the CPU's");
    println!(
        "first: ω = {:?}, pdf = {}",
        results[0].direction, results[0].pdf
    );
}

/// Composes `MY_CODE` with mcg's modules (naga_oil) and builds its compute pipeline.
fn compose_pipeline(device: &wgpu::Device) -> wgpu::ComputePipeline {
    let mut composer = Composer::default();
    shaders::add_to_composer(&mut composer).expect("mcg's modules compose");
    let naga_module = match composer.make_naga_module(NagaModuleDescriptor {
        source: MY_CODE,
        file_path: "examples/own_pipeline.wgsl",
        ..Default::default()
    }) {
        Ok(module) => module,
        Err(e) => panic!("{}", e.emit_to_string(&composer)),
    };
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("my shader"),
        source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(naga_module)),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("my pipeline"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// Runs `pipeline` over `uniforms` (one thread each) and reads its output back.
fn dispatch(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    pipeline: &wgpu::ComputePipeline,
    uniforms: &[[f32; 2]],
) -> Vec<Out> {
    let n = uniforms.len();
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("uniforms"),
        contents: bytemuck::cast_slice(uniforms),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (n * size_of::<Out>()) as u64;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("out"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("staging"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: input.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: output.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups((n as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &staging, 0, size);
    queue.submit([encoder.finish()]);
    staging
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.expect("map"));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("poll");
    let view = staging.slice(..).get_mapped_range().expect("mapped");
    bytemuck::pod_collect_to_vec(&view)
}

/// Checks every checksum against the CPU's and returns the largest direction difference.
fn check_against_cpu(uniforms: &[[f32; 2]], results: &[Out]) -> f32 {
    let lobe = Vmf::new(Vec3::Z, 40.0).expect("valid lobe");
    let mut worst = 0.0_f32;
    for (u, g) in uniforms.iter().zip(results) {
        let (w, _pdf) = lobe.sample_with_pdf(Vec2::from_array(*u));
        worst = worst.max((Vec3::from_array(g.direction) - w).length());
        let gw = Vec3::from_array(g.direction);
        let key = CellKey::new(
            IVec3::new(
                (gw.x / 0.1).floor() as i32,
                (gw.y / 0.1).floor() as i32,
                (gw.z / 0.1).floor() as i32,
            ),
            0,
            mcg_gpu_backend::mcg_hashgrid::normal_class(gw),
        );
        assert_eq!(g.key_checksum, checksum(&key), "checksum of {key:?}");
    }
    worst
}
