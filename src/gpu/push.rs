//! Push constants as typed Rust structs whose layout is checked against the GLSL block.
//!
//! A push-constant struct is declared with [`crate::push_constants!`], which makes it
//! `#[repr(C)]` and `Pod` and records every member's name, byte offset, size and scalar type
//! ([`PushConstants::MEMBERS`]). A pipeline is built with the struct's [`PushLayout`]; building
//! it compares the layout member by member with the block its shaders' SPIR-V declares
//! ([`super::reflect::check_layout`]: offsets, sizes, scalar types), and recording it accepts
//! only that struct. So a member added, moved, resized or retyped in GLSL without the same
//! change in Rust is refused naming the pipeline and the member, before anything is pushed.

use std::any::TypeId;

/// The scalar type a push-constant member is made of.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Scalar {
    /// 32-bit float (`float`, `vec*`, `mat*`).
    F32,
    /// 32-bit unsigned integer (`uint`, `uvec*`).
    U32,
    /// 32-bit signed integer (`int`, `ivec*`).
    I32,
    /// Anything else (64-bit, booleans, nested structs): matched by size only.
    Other,
}

/// One member of a push-constant struct as laid out in memory.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct PushMember {
    /// Its Rust name.
    pub name: &'static str,
    /// Byte offset from the start of the block.
    pub offset: u32,
    /// Bytes it occupies.
    pub size: u32,
    /// What it is made of.
    pub scalar: Scalar,
}

/// A Rust type pushed as a GLSL push-constant block; implement it with
/// [`crate::push_constants!`].
pub trait PushConstants: bytemuck::Pod {
    /// Its members in declaration order.
    const MEMBERS: &'static [PushMember];
}

/// No push constants.
impl PushConstants for () {
    const MEMBERS: &'static [PushMember] = &[];
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for u32 {}
    impl Sealed for i32 {}
    impl<T: Sealed, const N: usize> Sealed for [T; N] {}
}

/// The element type of a push-constant member: `f32`, `u32`, `i32` and arrays of them (sealed:
/// [`crate::push_constants!`] relies on every such type being plain old data).
pub trait PushScalar: sealed::Sealed {
    /// The scalar type.
    const SCALAR: Scalar;
}

impl PushScalar for f32 {
    const SCALAR: Scalar = Scalar::F32;
}

impl PushScalar for u32 {
    const SCALAR: Scalar = Scalar::U32;
}

impl PushScalar for i32 {
    const SCALAR: Scalar = Scalar::I32;
}

impl<T: PushScalar, const N: usize> PushScalar for [T; N] {
    const SCALAR: Scalar = T::SCALAR;
}

/// The push-constant layout a pipeline is built with: a [`PushConstants`] type's size and
/// members.
#[derive(Copy, Clone, Debug)]
pub struct PushLayout {
    /// Bytes of the block (0: none).
    pub bytes: u32,
    /// Its members.
    pub members: &'static [PushMember],
    /// The Rust type (recordings must push exactly this type).
    pub type_id: TypeId,
    /// The Rust type's name (for errors).
    pub type_name: &'static str,
}

impl PushLayout {
    /// The layout of `T`.
    pub fn of<T: PushConstants + 'static>() -> Self {
        Self {
            bytes: std::mem::size_of::<T>() as u32,
            members: T::MEMBERS,
            type_id: TypeId::of::<T>(),
            type_name: std::any::type_name::<T>(),
        }
    }

    /// No push constants.
    pub fn none() -> Self {
        Self::of::<()>()
    }
}

/// Declares a push-constant struct: `#[repr(C)]`, `Clone`, `Copy`, `Pod`, `Zeroable`, and a
/// [`PushConstants`] implementation listing its members (name, offset, size, scalar type).
/// Members are `f32`, `u32`, `i32` or arrays of them, laid out as the GLSL block (std430:
/// `vec4`/`mat4` members on 16-byte boundaries; pad with explicit members). A struct with
/// padding between or after its members does not compile.
///
/// ```
/// galerkin::push_constants! {
///     /// `layout(push_constant) uniform P { mat4 view_proj; uvec4 flags; }`
///     pub struct P {
///         view_proj: [f32; 16],
///         flags: [u32; 4],
///     }
/// }
/// use galerkin::gpu::PushConstants;
/// assert_eq!(P::MEMBERS[1].offset, 64);
/// ```
#[macro_export]
macro_rules! push_constants {
    ($(#[$meta:meta])* $vis:vis struct $name:ident { $($(#[$fmeta:meta])* $fvis:vis $field:ident : $ty:ty),* $(,)? }) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy)]
        $vis struct $name {
            $($(#[$fmeta])* $fvis $field: $ty),*
        }

        // No padding: the struct is exactly its members.
        const _: () = assert!(
            ::std::mem::size_of::<$name>() == 0 $(+ ::std::mem::size_of::<$ty>())*,
            "a push-constant struct must have no padding"
        );

        // SAFETY: every member is f32, u32, i32 or an array of them (`PushScalar` below), all
        // zeroable, and the struct is `repr(C)` without padding (asserted above).
        unsafe impl $crate::gpu::bytemuck::Zeroable for $name {}
        // SAFETY: as above; every bit pattern of those members is valid.
        unsafe impl $crate::gpu::bytemuck::Pod for $name {}

        impl $crate::gpu::PushConstants for $name {
            const MEMBERS: &'static [$crate::gpu::PushMember] = &[$(
                $crate::gpu::PushMember {
                    name: stringify!($field),
                    offset: ::std::mem::offset_of!($name, $field) as u32,
                    size: ::std::mem::size_of::<$ty>() as u32,
                    scalar: <$ty as $crate::gpu::PushScalar>::SCALAR,
                }
            ),*];
        }
    };
}
