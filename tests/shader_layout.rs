//! Pipelines check their Rust-side layout against the SPIR-V of their shaders (reflected with
//! `rspirv-reflect`): every embedded shader reflects; a push-constant size, binding kind or
//! binding count that disagrees with the GLSL is refused naming the pipeline; and workgroup
//! sizes come from the shader. (Every pipeline the engine builds goes through the same check,
//! so the rest of the suite also fails if any Rust struct disagrees with its GLSL block.)

mod common;

use galerkin::gpu::reflect::reflect;
use galerkin::gpu::{shaders, BindingKind, ComputePipeline, ComputePipelineDesc, GpuError};

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

#[test]
fn a_layout_that_disagrees_with_the_shader_is_refused_naming_the_pipeline() {
    let gpu = common::gpu();
    let push = reflect("axpy", galerkin::demo::shaders::AXPY).unwrap().push_bytes;
    let desc = |push_constant_bytes: u32, bindings: &'static [BindingKind]| ComputePipelineDesc {
        name: "axpy under test",
        spirv: galerkin::demo::shaders::AXPY,
        bindings,
        push_constant_bytes,
        specialization: &[],
        shared_bytes: 0,
    };
    let refused = |d: ComputePipelineDesc<'_>, what: &str| match ComputePipeline::new(&gpu, &d) {
        Err(GpuError::ShaderLayout { pipeline, detail }) => {
            assert_eq!(pipeline, "axpy under test");
            assert!(detail.contains(what), "{detail}");
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a disagreeing layout was accepted ({what})"),
    };
    refused(desc(push + 4, &[BindingKind::StorageBuffer, BindingKind::StorageBuffer]), "push-constant");
    refused(desc(push, &[BindingKind::StorageBuffer, BindingKind::UniformBuffer]), "binding 1");
    refused(desc(push, &[BindingKind::StorageBuffer]), "binding 1");
    let ok =
        ComputePipeline::new(&gpu, &desc(push, &[BindingKind::StorageBuffer, BindingKind::StorageBuffer]))
            .expect("the shader's own layout");
    assert_eq!(ok.local_size(), [256, 1, 1]);
}
