//! What a shader declares, read from its SPIR-V (with the `rspirv-reflect` and `rspirv`
//! crates): its push-constant block member by member (offset, size, scalar type), its
//! descriptor bindings in set 0, a compute shader's workgroup size and the bytes of workgroup
//! (`shared`) memory it declares. Pipelines check their Rust-side description against it when
//! they are built ([`check_layout`]), so a layout change in GLSL cannot silently disagree with
//! the struct pushed from Rust or with the bindings bound to it, and workgroup limits are
//! checked against what the shader really declares.

use std::collections::{BTreeMap, HashMap};

use rspirv::dr::{Instruction, Module, Operand};
use rspirv::spirv::{Decoration, Op, StorageClass, Word};
use rspirv_reflect::{DescriptorType, Reflection};

use super::descriptors::BindingKind;
use super::error::{GpuError, GpuResult};
use super::push::{PushLayout, Scalar};

/// A shader's declared interface.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ShaderLayout {
    /// Bytes of its push-constant block (0 without one).
    pub push_bytes: u32,
    /// Its set-0 bindings by binding number.
    pub bindings: BTreeMap<u32, BindingKind>,
    /// The `LocalSize` of a compute shader.
    pub local_size: Option<[u32; 3]>,
    /// The members of its push-constant block the module declares (the compiler may drop
    /// members a stage does not use), by offset.
    pub push_members: Vec<BlockMember>,
    /// Bytes of workgroup (`shared`) memory it declares.
    pub shared_bytes: u32,
    /// The storage-buffer bindings it may write (those not declared `readonly`, i.e. not
    /// decorated `NonWritable` as a variable or in every member of their block).
    pub writable: std::collections::BTreeSet<u32>,
}

/// One member of a push-constant block as a shader's SPIR-V lays it out.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct BlockMember {
    /// Byte offset (its `Offset` decoration).
    pub offset: u32,
    /// Bytes it occupies (arrays and matrices by their strides).
    pub size: u32,
    /// What it is made of.
    pub scalar: Scalar,
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
    let module = rspirv::dr::load_words(spirv)
        .map_err(|e| layout_err(pipeline, format!("cannot parse its SPIR-V: {e}")))?;
    let types = Types::new(&module);
    let mut push_members = Vec::new();
    let mut shared_bytes = 0u32;
    let mut writable = std::collections::BTreeSet::new();
    for var in module.types_global_values.iter().filter(|i| i.class.opcode == Op::Variable) {
        let (Some(ptr), Some(Operand::StorageClass(class))) = (var.result_type, var.operands.first()) else {
            continue;
        };
        let Some(pointee) = types.pointee(ptr) else { continue };
        match class {
            StorageClass::PushConstant => push_members = types.block_members(pointee),
            StorageClass::Workgroup => {
                shared_bytes = shared_bytes.saturating_add(types.size_of(pointee, None).map_or(0, |t| t.0))
            }
            StorageClass::StorageBuffer | StorageClass::Uniform => {
                let Some(id) = var.result_id else { continue };
                let Some(binding) = types.decoration(id, u32::MAX, Decoration::Binding) else { continue };
                if bindings.get(&binding) == Some(&BindingKind::StorageBuffer)
                    && !types.read_only(id, pointee)
                {
                    writable.insert(binding);
                }
            }
            _ => {}
        }
    }
    Ok(ShaderLayout { push_bytes, bindings, local_size, push_members, shared_bytes, writable })
}

/// The type declarations and decorations of a module, for sizes and layouts.
struct Types<'m> {
    by_id: HashMap<Word, &'m Instruction>,
    /// `(target, member or u32::MAX) → [(decoration, first literal)]`.
    decorations: HashMap<(Word, u32), Vec<(Decoration, u32)>>,
}

impl<'m> Types<'m> {
    fn new(module: &'m Module) -> Self {
        let by_id = module.types_global_values.iter().filter_map(|i| i.result_id.map(|id| (id, i))).collect();
        let mut decorations: HashMap<(Word, u32), Vec<(Decoration, u32)>> = HashMap::new();
        for a in &module.annotations {
            let literal = |k: usize| match a.operands.get(k) {
                Some(Operand::LiteralInt32(v)) => *v,
                _ => 0,
            };
            match (a.class.opcode, a.operands.as_slice()) {
                (Op::Decorate, [Operand::IdRef(t), Operand::Decoration(d), ..]) => {
                    decorations.entry((*t, u32::MAX)).or_default().push((*d, literal(2)))
                }
                (
                    Op::MemberDecorate,
                    [Operand::IdRef(t), Operand::LiteralInt32(m), Operand::Decoration(d), ..],
                ) => decorations.entry((*t, *m)).or_default().push((*d, literal(3))),
                _ => {}
            }
        }
        Self { by_id, decorations }
    }

    fn decoration(&self, target: Word, member: u32, which: Decoration) -> Option<u32> {
        self.decorations.get(&(target, member))?.iter().find(|(d, _)| *d == which).map(|(_, v)| *v)
    }

    fn id_operand(i: &Instruction, k: usize) -> Option<Word> {
        match i.operands.get(k) {
            Some(Operand::IdRef(id)) => Some(*id),
            _ => None,
        }
    }

    fn literal(i: &Instruction, k: usize) -> Option<u32> {
        match i.operands.get(k) {
            Some(Operand::LiteralInt32(v)) => Some(*v),
            _ => None,
        }
    }

    /// True if the buffer variable `var` (of block type `block`) is declared `readonly`.
    fn read_only(&self, var: Word, block: Word) -> bool {
        let non_writable = |t, m| {
            self.decorations
                .get(&(t, m))
                .is_some_and(|d| d.iter().any(|(d, _)| *d == Decoration::NonWritable))
        };
        if non_writable(var, u32::MAX) {
            return true;
        }
        let members = self.by_id.get(&block).map_or(0, |i| i.operands.len() as u32);
        members > 0 && (0..members).all(|m| non_writable(block, m))
    }

    /// The type a pointer type points to.
    fn pointee(&self, ptr: Word) -> Option<Word> {
        let p = self.by_id.get(&ptr)?;
        (p.class.opcode == Op::TypePointer).then(|| Self::id_operand(p, 1)).flatten()
    }

    /// Bytes and scalar type of `ty`; `matrix_stride` for a matrix member of a block.
    fn size_of(&self, ty: Word, matrix_stride: Option<u32>) -> Option<(u32, Scalar)> {
        let i = self.by_id.get(&ty)?;
        Some(match i.class.opcode {
            Op::TypeFloat => {
                let width = Self::literal(i, 0)?;
                (width / 8, if width == 32 { Scalar::F32 } else { Scalar::Other })
            }
            Op::TypeInt => {
                let (width, signed) = (Self::literal(i, 0)?, Self::literal(i, 1)?);
                let scalar = match (width, signed) {
                    (32, 0) => Scalar::U32,
                    (32, _) => Scalar::I32,
                    _ => Scalar::Other,
                };
                (width / 8, scalar)
            }
            Op::TypeBool => (4, Scalar::Other),
            Op::TypeVector => {
                let (size, scalar) = self.size_of(Self::id_operand(i, 0)?, None)?;
                (size * Self::literal(i, 1)?, scalar)
            }
            Op::TypeMatrix => {
                let column = Self::id_operand(i, 0)?;
                let (size, scalar) = self.size_of(column, None)?;
                (matrix_stride.unwrap_or(size) * Self::literal(i, 1)?, scalar)
            }
            Op::TypeArray => {
                let element = Self::id_operand(i, 0)?;
                let length = self.by_id.get(&Self::id_operand(i, 1)?).and_then(|c| Self::literal(c, 0))?;
                let (size, scalar) = self.size_of(element, matrix_stride)?;
                let stride = self.decoration(ty, u32::MAX, Decoration::ArrayStride).unwrap_or(size);
                (stride * length, scalar)
            }
            Op::TypeStruct => {
                let members = self.block_members(ty);
                let end = members.iter().map(|m| m.offset + m.size).max().unwrap_or(0);
                (end, Scalar::Other)
            }
            _ => return None,
        })
    }

    /// The members of struct `ty` with their `Offset` decorations (a struct without offsets
    /// is laid out naturally, in order).
    fn block_members(&self, ty: Word) -> Vec<BlockMember> {
        let Some(i) = self.by_id.get(&ty).filter(|i| i.class.opcode == Op::TypeStruct) else {
            return Vec::new();
        };
        let mut next = 0;
        let mut members = Vec::new();
        for (k, op) in i.operands.iter().enumerate() {
            let Operand::IdRef(member_ty) = op else { continue };
            let stride = self.decoration(ty, k as u32, Decoration::MatrixStride);
            let Some((size, scalar)) = self.size_of(*member_ty, stride) else { continue };
            let offset = self.decoration(ty, k as u32, Decoration::Offset).unwrap_or(next);
            next = offset + size;
            members.push(BlockMember { offset, size, scalar });
        }
        members
    }
}

/// The interface of a pipeline's stages together: the largest push-constant block (stages see
/// the same block, some only its start), every member any stage declares (which must agree
/// where two stages declare one at the same offset), and every binding, which must agree in
/// kind.
pub fn merge(pipeline: &str, stages: &[ShaderLayout]) -> GpuResult<ShaderLayout> {
    let mut out = ShaderLayout::default();
    for s in stages {
        out.push_bytes = out.push_bytes.max(s.push_bytes);
        for m in &s.push_members {
            match out.push_members.iter().find(|o| o.offset == m.offset) {
                Some(o) if o != m => {
                    return Err(layout_err(
                        pipeline,
                        format!(
                            "its stages disagree on the push-constant member at byte {}: {o:?} and {m:?}",
                            m.offset
                        ),
                    ))
                }
                Some(_) => {}
                None => out.push_members.push(*m),
            }
        }
        out.shared_bytes = out.shared_bytes.max(s.shared_bytes);
        out.writable.extend(&s.writable);
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
    push: &PushLayout,
    bindings: &[BindingKind],
) -> GpuResult<()> {
    if shaders.push_bytes != push.bytes {
        return Err(layout_err(
            pipeline,
            format!(
                "its shaders' push-constant block is {} bytes but `{}` is {} (the Rust struct and the GLSL block disagree)",
                shaders.push_bytes, push.type_name, push.bytes
            ),
        ));
    }
    for m in &shaders.push_members {
        let rust = push.members.iter().find(|r| r.offset == m.offset);
        match rust {
            Some(r) if r.size == m.size && (r.scalar == m.scalar || m.scalar == Scalar::Other) => {}
            Some(r) => {
                return Err(layout_err(
                    pipeline,
                    format!(
                        "push-constant member `{}` of `{}` (byte {}, {} bytes of {:?}) disagrees with the shader's ({} bytes of {:?})",
                        r.name, push.type_name, r.offset, r.size, r.scalar, m.size, m.scalar
                    ),
                ))
            }
            None => {
                return Err(layout_err(
                    pipeline,
                    format!(
                        "the shader has a push-constant member at byte {} ({} bytes of {:?}); no member of `{}` starts there",
                        m.offset, m.size, m.scalar, push.type_name
                    ),
                ))
            }
        }
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

#[cfg(test)]
mod tests {
    use super::reflect;

    /// `readonly buffer` bindings are read only; the others may be written (the declared
    /// accesses of a dispatch follow this). The GEMM reads A (0) and B (1) and writes C (2).
    #[test]
    fn readonly_buffers_are_told_from_written_ones() {
        let gemm = reflect("gemm", crate::tensor::shaders::GEMM).expect("reflects");
        assert_eq!(gemm.writable.iter().copied().collect::<Vec<_>>(), vec![2]);
        let axpy = reflect("axpy", crate::demo::shaders::AXPY).expect("reflects");
        assert!(!axpy.writable.is_empty(), "AXPY writes its output");
        assert!(axpy.writable.len() < axpy.bindings.len(), "and only reads its inputs: {:?}", axpy.writable);
    }
}
