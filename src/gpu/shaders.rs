//! Every GLSL shader under `shaders-glsl/`, compiled to SPIR-V by `build.rs` (glslc,
//! `--target-env=vulkan1.2 -O`) and embedded as `&'static [u32]` words — aligned by
//! construction, never a cast of `include_bytes!`. `shaders-glsl/demo/axpy.comp` is
//! `crate::demo::shaders::AXPY`; graphics stages carry their stage: `demo/field.vert` is
//! `crate::demo::shaders::FIELD_VERT`. [`ALL`] lists them for `galerkin info`.

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// Compiles GLSL at run time with the `shaderc` crate (feature `runtime-shaderc`, linked
/// against the system's shaderc and glslang; see build.rs): Vulkan 1.2 SPIR-V, optimised for
/// performance. `#include "name"` resolves to the files of `shaders-glsl/include/`
/// ([`INCLUDES`]). Compiler messages come back as the error, never a panic.
#[cfg(feature = "runtime-shaderc")]
pub fn compile_glsl(source: &str, file_name: &str, stage: shaderc::ShaderKind) -> Result<Vec<u32>, String> {
    let compiler = shaderc::Compiler::new().map_err(|e| e.to_string())?;
    let mut options = shaderc::CompileOptions::new().map_err(|e| e.to_string())?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    options.set_include_callback(|name, _kind, _from, _depth| {
        INCLUDES
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(n, text)| shaderc::ResolvedInclude {
                resolved_name: (*n).to_string(),
                content: (*text).to_string(),
            })
            .ok_or_else(|| format!("no include file {name:?} in shaders-glsl/include"))
    });
    compiler
        .compile_into_spirv(source, stage, file_name, "main", Some(&options))
        .map(|a| a.as_binary().to_vec())
        .map_err(|e| e.to_string())
}
