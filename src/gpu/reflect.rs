//! What a shader declares, read from its SPIR-V (with the `rspirv-reflect` crate): the size of
//! its push-constant block, its descriptor bindings in set 0, and a compute shader's workgroup
//! size. Pipelines check their Rust-side description against it when they are built
//! ([`check_layout`]), so a layout change in GLSL cannot silently disagree with the struct
//! pushed from Rust or with the bindings bound to it.

use std::collections::BTreeMap;

use rspirv_reflect::{DescriptorType, Reflection};

use super::descriptors::BindingKind;
use super::error::{GpuError, GpuResult};

/// A shader's declared interface.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ShaderLayout {
    /// Bytes of its push-constant block (0 without one).
    pub push_bytes: u32,
    /// Its set-0 bindings by binding number.
    pub bindings: BTreeMap<u32, BindingKind>,
    /// The `LocalSize` of a compute shader.
    pub local_size: Option<[u32; 3]>,
}

fn layout_err(pipeline: &str, detail: String) -> GpuError {
    GpuError::ShaderLayout { pipeline: pipeline.to_string(), detail }
}

/// Reflects `spirv` (a module of pipeline `pipeline`, named in errors).
pub fn reflect(pipeline: &str, spirv: &[u32]) -> GpuResult<ShaderLayout> {
    let r = Reflection::new_from_spirv(bytemuck::cast_slice(spirv))
        .map_err(|e| layout_err(pipeline, format!("cannot reflect its SPIR-V: {e}")))?;
    let push_bytes = r
        .get_push_constant_range()
        .map_err(|e| layout_err(pipeline, format!("push constants: {e}")))?
        .map_or(0, |p| p.offset + p.size);
    let sets = r.get_descriptor_sets().map_err(|e| layout_err(pipeline, format!("descriptor sets: {e}")))?;
    if let Some(other) = sets.keys().find(|&&s| s != 0) {
        return Err(layout_err(
            pipeline,
            format!("declares descriptor set {other}; galerkin binds set 0 only"),
        ));
    }
    let mut bindings = BTreeMap::new();
    for (&binding, info) in sets.get(&0).into_iter().flatten() {
        let kind = match info.ty {
            DescriptorType::STORAGE_BUFFER => BindingKind::StorageBuffer,
            DescriptorType::UNIFORM_BUFFER => BindingKind::UniformBuffer,
            DescriptorType::COMBINED_IMAGE_SAMPLER => BindingKind::Texture,
            other => {
                return Err(layout_err(
                    pipeline,
                    format!(
                        "binding {binding} (`{}`) has descriptor type {}, which galerkin does not bind",
                        info.name, other.0
                    ),
                ))
            }
        };
        bindings.insert(binding, kind);
    }
    let local_size = r.get_compute_group_size().map(|(x, y, z)| [x, y, z]);
    Ok(ShaderLayout { push_bytes, bindings, local_size })
}

/// The interface of a pipeline's stages together: the largest push-constant block (stages see
/// the same block, some only its start) and every binding, which must agree in kind.
pub fn merge(pipeline: &str, stages: &[ShaderLayout]) -> GpuResult<ShaderLayout> {
    let mut out = ShaderLayout::default();
    for s in stages {
        out.push_bytes = out.push_bytes.max(s.push_bytes);
        for (&b, &k) in &s.bindings {
            if let Some(&other) = out.bindings.get(&b) {
                if other != k {
                    return Err(layout_err(
                        pipeline,
                        format!("binding {b} is {other:?} in one stage, {k:?} in another"),
                    ));
                }
            }
            out.bindings.insert(b, k);
        }
        out.local_size = out.local_size.or(s.local_size);
    }
    Ok(out)
}

/// Checks a pipeline's description against its shaders: the declared push-constant bytes are
/// exactly the shaders' block (a Rust struct that disagrees with the GLSL block is refused
/// before anything is pushed), and every binding the shaders use is declared with its kind
/// (the description may declare more: a binding the compiler removed as unused).
pub fn check_layout(
    pipeline: &str,
    shaders: &ShaderLayout,
    push_bytes: u32,
    bindings: &[BindingKind],
) -> GpuResult<()> {
    if shaders.push_bytes != push_bytes {
        return Err(layout_err(
            pipeline,
            format!(
                "its shaders' push-constant block is {} bytes but {} are pushed (the Rust struct and the GLSL block disagree)",
                shaders.push_bytes, push_bytes
            ),
        ));
    }
    for (&b, &k) in &shaders.bindings {
        match bindings.get(b as usize) {
            Some(&declared) if declared == k => {}
            Some(&declared) => {
                return Err(layout_err(
                    pipeline,
                    format!("binding {b} is {k:?} in the shader but declared {declared:?}"),
                ))
            }
            None => {
                return Err(layout_err(
                    pipeline,
                    format!("the shader uses binding {b} ({k:?}); {} are declared", bindings.len()),
                ))
            }
        }
    }
    Ok(())
}
