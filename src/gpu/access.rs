//! Declared access: every command a [`super::Recorder`] records states which buffers and
//! images it reads and writes, in which pipeline stages, and the recorder derives the barriers
//! between commands from those declarations (the render-graph idea of screen-13 and kajiya,
//! kept to one command buffer): a read after a write waits for the write and makes it visible,
//! a write after reads or a write waits for them, an image in the wrong layout is transitioned,
//! and nothing is ordered that does not need to be.
//!
//! Barriers are recorded with `vkCmdPipelineBarrier2` where the device enabled
//! synchronization2 (every Vulkan 1.3 device galerkin creates), and with `vkCmdPipelineBarrier`
//! otherwise; declarations use the synchronization2 flags either way (only the bits that
//! Vulkan 1.0 also has).
//!
//! Across recordings: an object that earlier, still pending recordings use (its
//! [`super::Lifetime::pending`] count) is assumed written by them in any stage, so its first
//! access in a new recording waits for all earlier commands; an object no pending recording
//! uses needs no barrier (its fence was seen signalled). Images remember the layout their last
//! recorded command left them in.

use std::collections::HashMap;

use ash::vk;

/// How one command uses a buffer or image: the stages it touches it in and the kinds of
/// access (synchronization2 flags, restricted to bits Vulkan 1.0 also has).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Access {
    /// The pipeline stages.
    pub stages: vk::PipelineStageFlags2,
    /// The memory accesses.
    pub access: vk::AccessFlags2,
}

const WRITES: vk::AccessFlags2 = vk::AccessFlags2::from_raw(
    vk::AccessFlags2::SHADER_WRITE.as_raw()
        | vk::AccessFlags2::TRANSFER_WRITE.as_raw()
        | vk::AccessFlags2::HOST_WRITE.as_raw()
        | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags2::MEMORY_WRITE.as_raw(),
);

const SHADER_READS: vk::AccessFlags2 = vk::AccessFlags2::from_raw(
    vk::AccessFlags2::SHADER_READ.as_raw() | vk::AccessFlags2::UNIFORM_READ.as_raw(),
);

impl Access {
    /// A transfer command reads it (copy source, blit source).
    pub const TRANSFER_READ: Self =
        Self { stages: vk::PipelineStageFlags2::TRANSFER, access: vk::AccessFlags2::TRANSFER_READ };
    /// A transfer command writes it (copy or blit destination, fill, update).
    pub const TRANSFER_WRITE: Self =
        Self { stages: vk::PipelineStageFlags2::TRANSFER, access: vk::AccessFlags2::TRANSFER_WRITE };
    /// The host reads it once the recording's work has finished (a download's staging).
    pub const HOST_READ: Self =
        Self { stages: vk::PipelineStageFlags2::HOST, access: vk::AccessFlags2::HOST_READ };
    /// A compute shader reads it (storage, uniform or sampled).
    pub const COMPUTE_READ: Self =
        Self { stages: vk::PipelineStageFlags2::COMPUTE_SHADER, access: SHADER_READS };
    /// A compute shader reads and writes it (a writable storage buffer).
    pub const COMPUTE_READ_WRITE: Self = Self {
        stages: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::from_raw(SHADER_READS.as_raw() | vk::AccessFlags2::SHADER_WRITE.as_raw()),
    };
    /// The vertex, tessellation, geometry and fragment shaders of a draw read it.
    pub const GRAPHICS_READ: Self = Self { stages: GRAPHICS_SHADERS, access: SHADER_READS };
    /// The shaders of a draw read and write it (storage buffers a fragment shader writes).
    pub const GRAPHICS_READ_WRITE: Self = Self {
        stages: GRAPHICS_SHADERS,
        access: vk::AccessFlags2::from_raw(SHADER_READS.as_raw() | vk::AccessFlags2::SHADER_WRITE.as_raw()),
    };
    /// A draw reads it as vertex attributes.
    pub const VERTEX_INPUT: Self = Self {
        stages: vk::PipelineStageFlags2::VERTEX_INPUT,
        access: vk::AccessFlags2::VERTEX_ATTRIBUTE_READ,
    };
    /// An indirect draw or dispatch reads its parameters from it.
    pub const INDIRECT: Self = Self {
        stages: vk::PipelineStageFlags2::DRAW_INDIRECT,
        access: vk::AccessFlags2::INDIRECT_COMMAND_READ,
    };
    /// Every earlier command may have written it (an object of a pending recording).
    pub(crate) const ANY_WRITE: Self =
        Self { stages: vk::PipelineStageFlags2::ALL_COMMANDS, access: vk::AccessFlags2::MEMORY_WRITE };

    /// The union of two accesses (one command using an object in two ways).
    pub fn and(self, other: Self) -> Self {
        Self { stages: self.stages | other.stages, access: self.access | other.access }
    }

    /// True if it writes.
    pub fn writes(&self) -> bool {
        self.access.intersects(WRITES)
    }
}

/// Every shader stage of a draw.
const GRAPHICS_SHADERS: vk::PipelineStageFlags2 = vk::PipelineStageFlags2::from_raw(
    vk::PipelineStageFlags2::VERTEX_SHADER.as_raw()
        | vk::PipelineStageFlags2::TESSELLATION_CONTROL_SHADER.as_raw()
        | vk::PipelineStageFlags2::TESSELLATION_EVALUATION_SHADER.as_raw()
        | vk::PipelineStageFlags2::GEOMETRY_SHADER.as_raw()
        | vk::PipelineStageFlags2::FRAGMENT_SHADER.as_raw(),
);

/// What a recording knows of one object: its last write (with the stages that write is
/// already visible to), the stages that read it since, and for an image its layout.
#[derive(Clone, Debug, Default)]
pub(crate) struct State {
    write: Option<Access>,
    visible: vk::PipelineStageFlags2,
    reads: vk::PipelineStageFlags2,
}

impl State {
    /// The state of an object first met in a recording: `pending_elsewhere` if earlier,
    /// unfinished recordings use it.
    pub(crate) fn first(pending_elsewhere: bool) -> Self {
        if pending_elsewhere {
            Self {
                write: Some(Access::ANY_WRITE),
                visible: vk::PipelineStageFlags2::empty(),
                reads: vk::PipelineStageFlags2::ALL_COMMANDS,
            }
        } else {
            Self::default()
        }
    }

    /// The state after `written` wrote the object, visible to nothing yet.
    pub(crate) fn written(written: Access) -> Self {
        Self {
            write: Some(written),
            visible: vk::PipelineStageFlags2::empty(),
            reads: vk::PipelineStageFlags2::empty(),
        }
    }

    /// The state after a render pass wrote the object as an attachment and its external
    /// dependency made the write visible to `visible`.
    pub(crate) fn attachment_written(visible: vk::PipelineStageFlags2) -> Self {
        Self {
            write: Some(Access {
                stages: vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                access: vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
            }),
            visible,
            reads: vk::PipelineStageFlags2::empty(),
        }
    }

    /// Records `access` by the next command; returns the dependency it needs (source, then
    /// destination), if any. `transition` forces one (a layout change is a write).
    pub(crate) fn access(&mut self, access: Access, transition: bool) -> Option<(Access, Access)> {
        let none = vk::AccessFlags2::empty();
        if access.writes() || transition {
            let src = match self.write {
                Some(w) => Access { stages: w.stages | self.reads, access: w.access },
                None => Access { stages: self.reads, access: none },
            };
            let needed = transition || !src.stages.is_empty();
            if access.writes() {
                *self = Self {
                    write: Some(access),
                    visible: vk::PipelineStageFlags2::empty(),
                    reads: vk::PipelineStageFlags2::empty(),
                };
            } else {
                // The transition is the write; it is visible to (and ordered before) `access`.
                *self = Self {
                    write: Some(Access { stages: access.stages, access: none }),
                    visible: access.stages,
                    reads: access.stages,
                };
            }
            return needed.then_some((src, access));
        }
        self.reads |= access.stages;
        match self.write {
            Some(w) if !self.visible.contains(access.stages) => {
                self.visible |= access.stages;
                Some((w, access))
            }
            _ => None,
        }
    }

    /// Records `access` by a draw inside a render pass, where no barrier may be recorded:
    /// returns false if one would have been needed after a write of this recording.
    pub(crate) fn access_in_pass(&mut self, access: Access) -> bool {
        let visible_enough = match self.write {
            Some(w) if w == Access::ANY_WRITE => true,
            Some(_) => self.visible.contains(access.stages),
            None => true,
        };
        if access.writes() {
            *self = Self {
                write: Some(access),
                visible: vk::PipelineStageFlags2::empty(),
                reads: vk::PipelineStageFlags2::empty(),
            };
        } else {
            self.reads |= access.stages;
        }
        visible_enough
    }
}

/// What a barrier names besides memory: an image's layout change.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Transition {
    pub image: vk::Image,
    pub aspect: vk::ImageAspectFlags,
    pub from: vk::ImageLayout,
    pub to: vk::ImageLayout,
}

/// Dependencies waiting to be recorded before the next command.
#[derive(Default)]
pub(crate) struct Pending {
    memory: Vec<(Access, Access)>,
    images: Vec<(Access, Access, Transition)>,
}

impl Pending {
    pub(crate) fn memory(&mut self, src: Access, dst: Access) {
        self.memory.push((src, dst));
    }

    pub(crate) fn image(&mut self, src: Access, dst: Access, t: Transition) {
        self.images.push((src, dst, t));
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.memory.is_empty() && self.images.is_empty()
    }

    /// Records the dependencies into `cmd` as one barrier and clears them. Stages outside
    /// `enabled` (those of shader stages the device was created without: tessellation,
    /// geometry) are left out of every mask.
    ///
    /// # Safety
    /// `cmd` is a command buffer of `device` in the recording state, outside a render pass;
    /// every image named is live; `sync2` only if the device enabled synchronization2.
    pub(crate) unsafe fn record(
        &mut self,
        device: &ash::Device,
        cmd: vk::CommandBuffer,
        sync2: bool,
        enabled: vk::PipelineStageFlags2,
    ) {
        if self.is_empty() {
            return;
        }
        let mask = |a: &Access| Access { stages: a.stages & enabled, access: a.access };
        for (s, d) in &mut self.memory {
            (*s, *d) = (mask(s), mask(d));
        }
        for (s, d, _) in &mut self.images {
            (*s, *d) = (mask(s), mask(d));
        }
        let range = |aspect| super::image::subresource(aspect);
        if sync2 {
            let memory: Vec<vk::MemoryBarrier2> = self
                .memory
                .iter()
                .map(|(s, d)| {
                    vk::MemoryBarrier2::default()
                        .src_stage_mask(s.stages)
                        .src_access_mask(s.access)
                        .dst_stage_mask(d.stages)
                        .dst_access_mask(d.access)
                })
                .collect();
            let images: Vec<vk::ImageMemoryBarrier2> = self
                .images
                .iter()
                .map(|(s, d, t)| {
                    vk::ImageMemoryBarrier2::default()
                        .src_stage_mask(s.stages)
                        .src_access_mask(s.access)
                        .dst_stage_mask(d.stages)
                        .dst_access_mask(d.access)
                        .old_layout(t.from)
                        .new_layout(t.to)
                        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .image(t.image)
                        .subresource_range(range(t.aspect))
                })
                .collect();
            let info = vk::DependencyInfo::default().memory_barriers(&memory).image_memory_barriers(&images);
            // SAFETY: per this function's contract.
            unsafe { device.cmd_pipeline_barrier2(cmd, &info) };
        } else {
            let (mut src, mut dst) = (vk::PipelineStageFlags::empty(), vk::PipelineStageFlags::empty());
            let mut memory = Vec::new();
            for (s, d) in &self.memory {
                src |= stages1(s.stages);
                dst |= stages1(d.stages);
                memory.push(
                    vk::MemoryBarrier::default()
                        .src_access_mask(access1(s.access))
                        .dst_access_mask(access1(d.access)),
                );
            }
            let mut images = Vec::new();
            for (s, d, t) in &self.images {
                src |= stages1(s.stages);
                dst |= stages1(d.stages);
                images.push(
                    vk::ImageMemoryBarrier::default()
                        .src_access_mask(access1(s.access))
                        .dst_access_mask(access1(d.access))
                        .old_layout(t.from)
                        .new_layout(t.to)
                        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .image(t.image)
                        .subresource_range(range(t.aspect)),
                );
            }
            if src.is_empty() {
                src = vk::PipelineStageFlags::TOP_OF_PIPE;
            }
            if dst.is_empty() {
                dst = vk::PipelineStageFlags::BOTTOM_OF_PIPE;
            }
            // SAFETY: per this function's contract.
            unsafe {
                device.cmd_pipeline_barrier(
                    cmd,
                    src,
                    dst,
                    vk::DependencyFlags::empty(),
                    &memory,
                    &[],
                    &images,
                )
            };
        }
        self.memory.clear();
        self.images.clear();
    }
}

/// The Vulkan 1.0 stage flags of a declaration (its bits are 1.0's).
fn stages1(s: vk::PipelineStageFlags2) -> vk::PipelineStageFlags {
    vk::PipelineStageFlags::from_raw((s.as_raw() & 0xFFFF_FFFF) as u32)
}

/// The Vulkan 1.0 access flags of a declaration.
fn access1(a: vk::AccessFlags2) -> vk::AccessFlags {
    vk::AccessFlags::from_raw((a.as_raw() & 0xFFFF_FFFF) as u32)
}

/// What one object is, to the tracker: an engine object (by its lifetime) or an image the
/// engine does not own (by its handle).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Key {
    Object(usize),
    Foreign(u64),
}

/// Per-recording state of every object declared so far.
#[derive(Default)]
pub(crate) struct Tracker {
    pub(crate) states: HashMap<Key, State>,
    pub(crate) pending: Pending,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_after_a_write_wait_once_per_stage() {
        let mut s = State::first(false);
        assert_eq!(s.access(Access::TRANSFER_WRITE, false), None, "nothing before the first write");
        let (src, dst) = s.access(Access::COMPUTE_READ, false).expect("read after write");
        assert_eq!((src, dst), (Access::TRANSFER_WRITE, Access::COMPUTE_READ));
        assert_eq!(s.access(Access::COMPUTE_READ, false), None, "already visible to compute");
        assert!(s.access(Access::VERTEX_INPUT, false).is_some(), "not yet visible to vertex input");
        // A write after reads waits for the reading stages, with no memory to make visible.
        let (src, _) = s.access(Access::COMPUTE_READ_WRITE, false).expect("write after read");
        assert!(src
            .stages
            .contains(vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::VERTEX_INPUT));
        assert_eq!(src.access, vk::AccessFlags2::TRANSFER_WRITE);
        // Write after write.
        assert_eq!(s.access(Access::TRANSFER_WRITE, false).map(|p| p.0), Some(Access::COMPUTE_READ_WRITE));
    }

    #[test]
    fn reads_alone_need_nothing_and_pending_objects_wait_for_everything() {
        let mut s = State::first(false);
        assert_eq!(s.access(Access::COMPUTE_READ, false), None);
        assert_eq!(s.access(Access::GRAPHICS_READ, false), None);
        let mut p = State::first(true);
        assert_eq!(p.access(Access::COMPUTE_READ, false).map(|d| d.0), Some(Access::ANY_WRITE));
        let mut w = State::first(true);
        let (src, _) = w.access(Access::TRANSFER_WRITE, false).expect("write after pending work");
        assert_eq!(src.stages, vk::PipelineStageFlags2::ALL_COMMANDS);
    }

    #[test]
    fn a_transition_is_a_write_ordered_before_its_reader() {
        let mut s = State::first(false);
        assert!(s.access(Access::TRANSFER_READ, true).is_some(), "a layout change always needs a barrier");
        assert_eq!(s.access(Access::TRANSFER_READ, false), None);
        assert!(s.access(Access::COMPUTE_READ, false).is_some(), "another stage waits for the transition");
    }

    #[test]
    fn draws_report_writes_a_barrier_should_have_covered() {
        let mut s = State::first(false);
        s.access(Access::COMPUTE_READ_WRITE, false);
        assert!(!s.access_in_pass(Access::VERTEX_INPUT), "a compute write not made visible to vertex input");
        let mut ok = State::first(false);
        ok.access(Access::COMPUTE_READ_WRITE, false);
        ok.access(Access::VERTEX_INPUT, false);
        assert!(ok.access_in_pass(Access::VERTEX_INPUT));
        assert!(
            State::first(true).access_in_pass(Access::GRAPHICS_READ),
            "earlier submissions are ordered by them"
        );
    }
}
