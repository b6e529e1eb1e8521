//! Pipelines check their Rust-side layout against the SPIR-V of their shaders (reflected with
//! `rspirv-reflect` and `rspirv`): every embedded shader reflects; a push-constant struct that
//! disagrees with the GLSL block — in size, or member by member in offset, size or scalar
//! type — and a binding kind or count that disagrees are refused naming the pipeline (and the
//! member); a recording must push the struct the pipeline was built with; workgroup sizes and
//! shared memory come from the shader. (Every pipeline the engine builds goes through the same check,
//! so the rest of the suite also fails if any Rust struct disagrees with its GLSL block.)

mod common;

use galerkin::gpu::reflect::{reflect, BlockMember};
use galerkin::gpu::{
    shaders, BindingKind, ComputePipeline, ComputePipelineDesc, GpuError, PushLayout, Scalar,
};
use galerkin::tensor::gpu::{GEMM_KT, GEMM_TILE};

#[test]
fn every_embedded_shader_reflects() {
    for (path, spirv) in shaders::ALL {
        let layout = reflect(path, spirv).unwrap_or_else(|e| panic!("{path}: {e}"));
        if path.ends_with(".comp") {
            assert!(layout.local_size.is_some(), "{path}: a compute shader without LocalSize");
        }
    }
    // axpy.comp: `layout(local_size_x = 256)` and two storage buffers.
    let axpy = reflect("axpy", galerkin::demo::shaders::AXPY).unwrap();
    assert_eq!(axpy.local_size, Some([256, 1, 1]));
    assert_eq!(axpy.bindings.values().copied().collect::<Vec<_>>(), vec![BindingKind::StorageBuffer; 2]);
}

galerkin::push_constants! {
    /// `axpy.comp`'s own block: `Push { float a; uint n; }`.
    struct AxpyPush {
        a: f32,
        n: u32,
    }
}

galerkin::push_constants! {
    /// One member too many.
    struct Longer {
        a: f32,
        n: u32,
        extra: u32,
    }
}

galerkin::push_constants! {
    /// The right size, the members swapped: `uint` where the shader has `float`.
    struct Swapped {
        n: u32,
        a: f32,
    }
}

galerkin::push_constants! {
    /// The right size, one `vec2`-like member where the shader has two scalars.
    struct Merged {
        both: [f32; 2],
    }
}

#[test]
fn a_layout_that_disagrees_with_the_shader_is_refused_naming_the_pipeline() {
    let gpu = common::gpu();
    let desc = |push: PushLayout, bindings: &'static [BindingKind]| ComputePipelineDesc {
        name: "axpy under test",
        spirv: galerkin::demo::shaders::AXPY,
        bindings,
        push,
        specialization: &[],
    };
    let refused = |d: ComputePipelineDesc<'_>, what: &str| match ComputePipeline::new(&gpu, &d) {
        Err(GpuError::ShaderLayout { pipeline, detail }) => {
            assert_eq!(pipeline, "axpy under test");
            assert!(detail.contains(what), "{detail}");
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a disagreeing layout was accepted ({what})"),
    };
    let two = &[BindingKind::StorageBuffer, BindingKind::StorageBuffer];
    refused(desc(PushLayout::of::<Longer>(), two), "push-constant block is 8 bytes but");
    refused(desc(PushLayout::of::<Swapped>(), two), "member `n` of");
    refused(desc(PushLayout::of::<Merged>(), two), "member `both` of");
    refused(desc(PushLayout::none(), two), "push-constant block is 8 bytes");
    refused(
        desc(PushLayout::of::<AxpyPush>(), &[BindingKind::StorageBuffer, BindingKind::UniformBuffer]),
        "binding 1",
    );
    refused(desc(PushLayout::of::<AxpyPush>(), &[BindingKind::StorageBuffer]), "binding 1");
    let ok = ComputePipeline::new(&gpu, &desc(PushLayout::of::<AxpyPush>(), two))
        .expect("the shader's own layout");
    assert_eq!(ok.local_size(), [256, 1, 1]);
}

#[test]
fn push_constant_members_and_shared_memory_are_read_from_the_spirv() {
    // axpy.comp: `Push { float a; uint n; }`.
    let axpy = reflect("axpy", galerkin::demo::shaders::AXPY).unwrap();
    assert_eq!(
        axpy.push_members,
        vec![
            BlockMember { offset: 0, size: 4, scalar: Scalar::F32 },
            BlockMember { offset: 4, size: 4, scalar: Scalar::U32 },
        ]
    );
    // The spectral draws' block: mat4, three vec4, a uvec4 (spectral_push.glsl).
    let frag = reflect("spectral", galerkin::spectral::shaders::ELEMENT_FRAG).unwrap();
    let planar = reflect("spectral", galerkin::spectral::shaders::ELEMENT_PLANAR_FRAG).unwrap();
    let vert = reflect("spectral", galerkin::spectral::shaders::ELEMENT_VERT).unwrap();
    let merged = galerkin::gpu::reflect::merge("spectral", &[vert, frag, planar]).unwrap();
    let mut members = merged.push_members.clone();
    members.sort_by_key(|m| m.offset);
    assert_eq!(members.first(), Some(&BlockMember { offset: 0, size: 64, scalar: Scalar::F32 }));
    assert_eq!(members.last(), Some(&BlockMember { offset: 112, size: 16, scalar: Scalar::U32 }));
    // Workgroup memory: the GEMM include's two shared tiles (GEMM_TILE × GEMM_KT floats each),
    // the same tiles in the fused premultiplication GEMM, the LU solve's reduction arrays
    // (64 floats and 64 uints), the U_max reduction's 64 floats, none in axpy.
    let tiles = 2 * GEMM_TILE * GEMM_KT * 4;
    assert_eq!(reflect("gemm", galerkin::tensor::shaders::GEMM).unwrap().shared_bytes, tiles);
    assert_eq!(reflect("fused", galerkin::tensor::shaders::PREMULTIPLY_GEMM).unwrap().shared_bytes, tiles);
    assert_eq!(reflect("lu", galerkin::tensor::shaders::LU_SOLVE).unwrap().shared_bytes, 64 * 8);
    assert_eq!(reflect("max_u", galerkin::spacetime::shaders::MAX_U).unwrap().shared_bytes, 64 * 4);
    assert_eq!(axpy.shared_bytes, 0);
}

#[test]
#[should_panic(expected = "pushes")]
fn recording_another_push_type_than_the_pipeline_was_built_with_panics() {
    let gpu = common::gpu();
    let pipeline = ComputePipeline::new(
        &gpu,
        &ComputePipelineDesc {
            name: "axpy",
            spirv: galerkin::demo::shaders::AXPY,
            bindings: &[BindingKind::StorageBuffer, BindingKind::StorageBuffer],
            push: PushLayout::of::<AxpyPush>(),
            specialization: &[],
        },
    )
    .unwrap();
    let usage = galerkin::gpu::vk::BufferUsageFlags::STORAGE_BUFFER;
    let x = galerkin::gpu::Buffer::from_slice(&gpu, "x", &[0f32; 4], usage).unwrap();
    let set = pipeline
        .bind(
            &gpu,
            &[galerkin::gpu::Resource::Storage(x.whole()), galerkin::gpu::Resource::Storage(x.whole())],
        )
        .unwrap();
    // Same size, another type: its layout was never checked against the shader.
    let _ = gpu.run(|rec| pipeline.record_dispatch(rec, &set, &Swapped { n: 1, a: 2.0 }, [1, 1, 1]));
}
