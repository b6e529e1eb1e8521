//! Every GLSL shader under `shaders-glsl/`, compiled to SPIR-V by `build.rs` (glslc,
//! `--target-env=vulkan1.2 -O`) and embedded as `&'static [u32]` words — aligned by
//! construction, never a cast of `include_bytes!`. `shaders-glsl/demo/axpy.comp` is
//! `crate::demo::shaders::AXPY`; graphics stages carry their stage: `demo/field.vert` is
//! `crate::demo::shaders::FIELD_VERT`. [`ALL`] lists them for `galerkin info`.

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// Compiles GLSL at run time with the `shaderc` crate (feature `runtime-shaderc`; it builds
/// glslang from source, about 20 minutes on 2 cores, so it is not in the default build).
#[cfg(feature = "runtime-shaderc")]
pub fn compile_glsl(source: &str, file_name: &str, stage: shaderc::ShaderKind) -> Result<Vec<u32>, String> {
    let compiler = shaderc::Compiler::new().map_err(|e| e.to_string())?;
    let mut options = shaderc::CompileOptions::new().map_err(|e| e.to_string())?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    compiler
        .compile_into_spirv(source, stage, file_name, "main", Some(&options))
        .map(|a| a.as_binary().to_vec())
        .map_err(|e| e.to_string())
}
