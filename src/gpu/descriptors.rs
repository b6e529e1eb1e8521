//! Descriptor set layouts and descriptor sets. A pipeline declares its bindings as a list of
//! [`BindingKind`]s (binding `i` is entry `i`, all in set 0); a [`DescriptorSet`] binds concrete
//! resources to them once and is reused every time the pass is recorded (resources stay
//! resident). Each set has its own small pool, so sets come and go independently, and keeps
//! every resource it binds alive until the set itself is destroyed (after the last recording
//! that uses it has finished).

use std::sync::Arc;

use ash::vk;

use super::buffer::BufferBinding;
use super::context::{DeviceShared, Gpu};
use super::error::{vk_error, GpuError, GpuResult, VkContext};
use super::image::{Image, Sampler};
use super::lifetime::{Lifetime, Tracked};

/// The kind of one binding.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum BindingKind {
    /// `layout(std430) buffer` — read/write storage buffer.
    StorageBuffer,
    /// `layout(std140) uniform` — uniform buffer.
    UniformBuffer,
    /// `sampler1D`/`sampler2D` — combined image sampler.
    Texture,
}

impl BindingKind {
    fn vk(self) -> vk::DescriptorType {
        match self {
            Self::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
            Self::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
            Self::Texture => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        }
    }
}

/// A concrete resource for one binding (borrowing it: see [`BufferBinding`]).
#[derive(Copy, Clone)]
pub enum Resource<'a> {
    /// A storage-buffer range.
    Storage(BufferBinding<'a>),
    /// A uniform-buffer range.
    Uniform(BufferBinding<'a>),
    /// An image, read in `SHADER_READ_ONLY_OPTIMAL` through its view, with a sampler.
    Texture {
        /// The image.
        image: &'a Image,
        /// The sampler.
        sampler: &'a Sampler,
    },
}

impl Resource<'_> {
    fn kind(&self) -> BindingKind {
        match self {
            Self::Storage(_) => BindingKind::StorageBuffer,
            Self::Uniform(_) => BindingKind::UniformBuffer,
            Self::Texture { .. } => BindingKind::Texture,
        }
    }

    /// The object a shader accesses through it (the buffer, or the image).
    fn accessed(&self) -> &Arc<Lifetime> {
        match self {
            Self::Storage(b) | Self::Uniform(b) => b.lifetime(),
            Self::Texture { image, .. } => image.lifetime(),
        }
    }

    /// The lifetimes a set binding this must keep.
    fn lifetimes(&self) -> Vec<Arc<Lifetime>> {
        match self {
            Self::Storage(b) | Self::Uniform(b) => vec![b.lifetime().clone()],
            Self::Texture { image, sampler } => vec![image.lifetime().clone(), sampler.lifetime().clone()],
        }
    }
}

/// A set layout: binding `i` has kind `kinds[i]`, visible to `stages`.
pub struct DescriptorSetLayout {
    life: Arc<Lifetime>,
    pub(crate) shared: Arc<DeviceShared>,
    pub(crate) raw: vk::DescriptorSetLayout,
    kinds: Vec<BindingKind>,
}

impl Tracked for DescriptorSetLayout {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.life
    }
}

impl DescriptorSetLayout {
    /// Creates the layout.
    pub fn new(gpu: &Gpu, kinds: &[BindingKind], stages: vk::ShaderStageFlags) -> GpuResult<Self> {
        let bindings: Vec<_> = kinds
            .iter()
            .enumerate()
            .map(|(i, k)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(k.vk())
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: valid create info on this device.
        let raw = unsafe { gpu.device().create_descriptor_set_layout(&info, None) }
            .vk("vkCreateDescriptorSetLayout")?;
        let life = Lifetime::new(&gpu.shared, "a descriptor set layout", move |dev| {
            // SAFETY: no pipeline layout, set or recording uses it any more.
            unsafe { dev.raw.destroy_descriptor_set_layout(raw, None) }
        });
        Ok(Self { life, shared: gpu.shared.clone(), raw, kinds: kinds.to_vec() })
    }

    /// The binding kinds, in binding order.
    pub fn kinds(&self) -> &[BindingKind] {
        &self.kinds
    }
}

/// Resources bound to a layout, in a pool of its own; it keeps them alive.
pub struct DescriptorSet {
    life: Arc<Lifetime>,
    _device: Arc<DeviceShared>,
    pub(crate) raw: vk::DescriptorSet,
    /// The buffer or image each binding names, by binding number (for declared access).
    bound: Vec<Arc<Lifetime>>,
}

impl Tracked for DescriptorSet {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.life
    }
}

impl DescriptorSet {
    /// Binds `resources` (one per binding of `layout`, same kinds, in order). A storage range
    /// larger than [`Gpu::max_binding_bytes`] is an error; a kind mismatch is a bug and panics.
    pub fn new(gpu: &Gpu, layout: &DescriptorSetLayout, resources: &[Resource]) -> GpuResult<Self> {
        assert_eq!(resources.len(), layout.kinds.len(), "descriptor set needs one resource per binding");
        let mut held: Vec<Arc<Lifetime>> = resources.iter().flat_map(Resource::lifetimes).collect();
        let bound: Vec<Arc<Lifetime>> = resources.iter().map(Resource::accessed).cloned().collect();
        if let Some(other) = held.iter().find(|l| !l.is_on(&gpu.shared)) {
            return Err(GpuError::WrongDevice { name: other.name().to_string() });
        }
        if !Arc::ptr_eq(&layout.shared, &gpu.shared) {
            return Err(GpuError::WrongDevice { name: "a descriptor set layout".into() });
        }
        // Commands that use the set may access its layout: it lives as long as the set.
        held.push(layout.life.clone());
        for (i, (r, k)) in resources.iter().zip(&layout.kinds).enumerate() {
            assert_eq!(r.kind(), *k, "binding {i}: resource kind does not match the layout");
            if let Resource::Storage(b) = r {
                if b.range > gpu.max_binding_bytes() {
                    return Err(GpuError::OverLimit {
                        name: format!("storage binding {i}"),
                        requested: b.range,
                        limit: gpu.max_binding_bytes(),
                        limit_name: "maxStorageBufferRange (bind it in chunks)",
                        unit: "bytes",
                    });
                }
            }
        }
        let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
        for k in &layout.kinds {
            match sizes.iter_mut().find(|s| s.ty == k.vk()) {
                Some(s) => s.descriptor_count += 1,
                None => sizes.push(vk::DescriptorPoolSize { ty: k.vk(), descriptor_count: 1 }),
            }
        }
        let info = vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes);
        // SAFETY: valid create info (an empty layout gets a pool with no sizes, which is valid).
        let pool =
            unsafe { gpu.device().create_descriptor_pool(&info, None) }.vk("vkCreateDescriptorPool")?;
        let layouts = [layout.raw];
        let alloc = vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts);
        // SAFETY: the pool has room for exactly this set.
        let raw = match unsafe { gpu.device().allocate_descriptor_sets(&alloc) } {
            Ok(s) => s[0],
            Err(e) => {
                // SAFETY: the pool is unused.
                unsafe { gpu.device().destroy_descriptor_pool(pool, None) };
                return Err(vk_error("vkAllocateDescriptorSets", e));
            }
        };
        let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = resources
            .iter()
            .map(|r| match r {
                Resource::Storage(b) | Resource::Uniform(b) => {
                    [vk::DescriptorBufferInfo { buffer: b.raw(), offset: b.offset, range: b.range }]
                }
                Resource::Texture { .. } => [vk::DescriptorBufferInfo::default()],
            })
            .collect();
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = resources
            .iter()
            .map(|r| match r {
                Resource::Texture { image, sampler } => [vk::DescriptorImageInfo {
                    sampler: sampler.raw(),
                    image_view: image.view(),
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }],
                _ => [vk::DescriptorImageInfo::default()],
            })
            .collect();
        let writes: Vec<vk::WriteDescriptorSet> = resources
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let w = vk::WriteDescriptorSet::default()
                    .dst_set(raw)
                    .dst_binding(i as u32)
                    .descriptor_type(r.kind().vk());
                match r {
                    Resource::Texture { .. } => w.image_info(&image_infos[i]),
                    _ => w.buffer_info(&buffer_infos[i]),
                }
            })
            .collect();
        // SAFETY: every write targets a binding of matching type; the infos outlive the call.
        unsafe { gpu.device().update_descriptor_sets(&writes, &[]) };
        let life = Lifetime::new(&gpu.shared, "a descriptor set", move |dev| {
            // SAFETY: no recording uses the set any more; destroying the pool frees it. The
            // resources it bound (`held`) are released after it.
            unsafe { dev.raw.destroy_descriptor_pool(pool, None) };
            drop(held);
        });
        Ok(Self { _device: gpu.shared.clone(), life, raw, bound })
    }

    /// The buffer or image each binding names, by binding number.
    pub(crate) fn bound(&self) -> &[Arc<Lifetime>] {
        &self.bound
    }

    /// The Vulkan handle.
    pub fn raw(&self) -> vk::DescriptorSet {
        self.raw
    }
}
