//! Descriptor set layouts and descriptor sets. A pipeline declares its bindings as a list of
//! [`BindingKind`]s (binding `i` is entry `i`, all in set 0); a [`DescriptorSet`] binds concrete
//! resources to them once and is reused every time the pass is recorded (resources stay
//! resident). Each set has its own small pool, so sets come and go independently.

use std::sync::Arc;

use ash::vk;

use super::buffer::BufferBinding;
use super::context::{DeviceShared, Gpu};
use super::error::{vk_error, GpuError, GpuResult, VkContext};

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

/// A concrete resource for one binding.
#[derive(Copy, Clone, Debug)]
pub enum Resource {
    /// A storage-buffer range.
    Storage(BufferBinding),
    /// A uniform-buffer range.
    Uniform(BufferBinding),
    /// An image view in `SHADER_READ_ONLY_OPTIMAL` with its sampler.
    Texture {
        /// The view.
        view: vk::ImageView,
        /// The sampler.
        sampler: vk::Sampler,
    },
}

impl Resource {
    fn kind(&self) -> BindingKind {
        match self {
            Self::Storage(_) => BindingKind::StorageBuffer,
            Self::Uniform(_) => BindingKind::UniformBuffer,
            Self::Texture { .. } => BindingKind::Texture,
        }
    }
}

/// A set layout: binding `i` has kind `kinds[i]`, visible to `stages`.
pub struct DescriptorSetLayout {
    shared: Arc<DeviceShared>,
    pub(crate) raw: vk::DescriptorSetLayout,
    kinds: Vec<BindingKind>,
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
        Ok(Self { shared: gpu.shared.clone(), raw, kinds: kinds.to_vec() })
    }

    /// The binding kinds, in binding order.
    pub fn kinds(&self) -> &[BindingKind] {
        &self.kinds
    }
}

impl Drop for DescriptorSetLayout {
    fn drop(&mut self) {
        let raw = self.raw;
        self.shared.retire(move |dev| {
            // SAFETY: nothing in flight uses the layout.
            unsafe { dev.raw.destroy_descriptor_set_layout(raw, None) }
        });
    }
}

/// Resources bound to a layout, in a pool of its own.
pub struct DescriptorSet {
    shared: Arc<DeviceShared>,
    pool: vk::DescriptorPool,
    pub(crate) raw: vk::DescriptorSet,
}

impl DescriptorSet {
    /// Binds `resources` (one per binding of `layout`, same kinds, in order). A storage range
    /// larger than [`Gpu::max_binding_bytes`] is an error; a kind mismatch is a bug and panics.
    pub fn new(gpu: &Gpu, layout: &DescriptorSetLayout, resources: &[Resource]) -> GpuResult<Self> {
        assert_eq!(resources.len(), layout.kinds.len(), "descriptor set needs one resource per binding");
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
                    [vk::DescriptorBufferInfo { buffer: b.buffer, offset: b.offset, range: b.range }]
                }
                Resource::Texture { .. } => [vk::DescriptorBufferInfo::default()],
            })
            .collect();
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = resources
            .iter()
            .map(|r| match r {
                Resource::Texture { view, sampler } => [vk::DescriptorImageInfo {
                    sampler: *sampler,
                    image_view: *view,
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
        Ok(Self { shared: gpu.shared.clone(), pool, raw })
    }

    /// The Vulkan handle.
    pub fn raw(&self) -> vk::DescriptorSet {
        self.raw
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        let pool = self.pool;
        self.shared.retire(move |dev| {
            // SAFETY: nothing in flight uses the set; destroying the pool frees it.
            unsafe { dev.raw.destroy_descriptor_pool(pool, None) }
        });
    }
}
