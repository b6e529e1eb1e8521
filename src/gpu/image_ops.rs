//! Safe, layout-tracked image operations on a [`Recorder`]: layout changes, blits and copies
//! between images and buffers, of engine [`super::Image`]s and of [`super::ForeignImage`]s
//! (a host's or a swapchain's). Each states its access ([`super::access`]); the recorder moves
//! the image to the layout the command needs and records the barrier in the same step, so no
//! caller names a layout it believes the image is in.
//!
//! Images that a command writes are taken by `&mut`, so the borrow checker refuses a blit of
//! an image onto itself and a write to an image while something else borrows it:
//!
//! ```compile_fail,E0502
//! # use galerkin::gpu::{vk, Image, Recorder};
//! # fn f(rec: &mut Recorder<'_>, image: &mut Image) {
//! let extent = image.extent();
//! rec.blit(&*image, image, extent); // error[E0502]: also borrowed as immutable
//! # }
//! ```
//!
//! ```compile_fail,E0308
//! # use galerkin::gpu::{vk, Buffer, Image, Recorder};
//! # fn f(rec: &mut Recorder<'_>, texels: &Buffer<u8>, image: &Image) {
//! // A copy writes the image: a shared reference is not enough.
//! rec.copy_buffer_to_image(texels, image, vk::Offset2D::default(), image.extent());
//! # }
//! ```
//!
//! ```compile_fail,E0308
//! # use galerkin::gpu::{vk, Access, Image, Recorder};
//! # fn f(rec: &mut Recorder<'_>, image: &Image) {
//! // A layout change is a write.
//! rec.transition(image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, Access::TRANSFER_READ);
//! # }
//! ```
//!
//! ```compile_fail,E0382
//! # use galerkin::gpu::{vk, Buffer, Image, Recorder};
//! # fn f(mut rec: Recorder<'_>, image: &Image, out: &Buffer<u8>) {
//! let recording = rec.finish();
//! // A finished recording cannot record more: a host may already have submitted it.
//! rec.copy_image_to_buffer(image, out);
//! # }
//! ```
//!
//! The same calls with the borrows right compile:
//!
//! ```no_run
//! # use galerkin::gpu::{vk, Access, Buffer, Image, Recorder};
//! # fn f(mut rec: Recorder<'_>, src: &Image, dst: &mut Image, texels: &Buffer<u8>, out: &Buffer<u8>) {
//! let extent = dst.extent();
//! rec.blit(src, dst, extent);
//! rec.copy_buffer_to_image(texels, dst, vk::Offset2D::default(), extent);
//! rec.transition(dst, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, Access::COMPUTE_READ);
//! rec.copy_image_to_buffer(src, out);
//! let recording = rec.finish();
//! # }
//! ```

use ash::vk;
use bytemuck::Pod;

use super::access::{Access, Transition};
use super::buffer::Buffer;
use super::image::{full_copy_region, texel_bytes, ImageResource};
use super::lifetime::Tracked;
use super::recorder::Recorder;

impl Recorder<'_> {
    /// Declares that the next command uses `image` as `access` in `layout`: keeps it, and
    /// queues the barrier (with the layout change, if any) the access needs.
    fn access_image(
        &mut self,
        image: &(impl ImageResource + ?Sized),
        access: Access,
        layout: vk::ImageLayout,
    ) {
        let t = image.tracking();
        let mut current = t.layout.lock().unwrap_or_else(|p| p.into_inner());
        let change = *current != layout;
        let state = self.state(t.key, t.life);
        if let Some((src, dst)) = state.access(access, change) {
            if change {
                let transition =
                    Transition { image: image.handle(), aspect: image.aspect(), from: *current, to: layout };
                self.tracker.pending.image(src, dst, transition);
            } else {
                self.tracker.pending.memory(src, dst);
            }
        }
        *current = layout;
        drop(current);
        if let Some(life) = t.life {
            self.keep_lifetime(life);
        }
    }

    /// Moves `image` to `layout` for the later commands that use it as `access` (for example
    /// `SHADER_READ_ONLY_OPTIMAL` for sampling, `PRESENT_SRC_KHR` with no access for
    /// presentation). Nothing is recorded if it is there already and visible to `access`.
    pub fn transition(
        &mut self,
        image: &mut (impl ImageResource + ?Sized),
        layout: vk::ImageLayout,
        access: Access,
    ) {
        self.access_image(image, access, layout);
        self.flush();
    }

    /// Records a nearest-texel blit of all of `src` onto the top-left `dst_extent` texels of
    /// `dst` (a scaling copy when the extents differ). Panics if `dst_extent` is outside
    /// `dst`, or is empty.
    pub fn blit(
        &mut self,
        src: &(impl ImageResource + ?Sized),
        dst: &mut (impl ImageResource + ?Sized),
        dst_extent: vk::Extent2D,
    ) {
        let (se, de) = (src.extent(), dst.extent());
        assert!(
            dst_extent.width >= 1
                && dst_extent.height >= 1
                && dst_extent.width <= de.width
                && dst_extent.height <= de.height,
            "a blit to {}×{} texels of an image of {}×{}",
            dst_extent.width,
            dst_extent.height,
            de.width,
            de.height
        );
        self.access_image(src, Access::TRANSFER_READ, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
        self.access_image(dst, Access::TRANSFER_WRITE, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        self.flush();
        let corner = |e: vk::Extent2D| {
            [vk::Offset3D::default(), vk::Offset3D { x: e.width as i32, y: e.height as i32, z: 1 }]
        };
        let layers = |aspect| vk::ImageSubresourceLayers {
            aspect_mask: aspect,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let blit = vk::ImageBlit {
            src_subresource: layers(src.aspect()),
            src_offsets: corner(se),
            dst_subresource: layers(dst.aspect()),
            dst_offsets: corner(dst_extent),
        };
        // SAFETY: both images are live (engine images kept by this recording, foreign ones by
        // their constructor's contract) and in the layouts just declared; the regions lie
        // inside them (checked above).
        unsafe {
            self.device().cmd_blit_image(
                self.cmd(),
                src.handle(),
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.handle(),
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[blit],
                vk::Filter::NEAREST,
            )
        };
    }

    /// Records a copy of tightly packed texels from the start of `src` into the `extent`
    /// texels of `dst` at `offset`. Panics if the region is outside `dst`, if `dst`'s format
    /// is not one galerkin knows the texel size of, or if `src` is too small.
    pub fn copy_buffer_to_image<T: Pod>(
        &mut self,
        src: &Buffer<T>,
        dst: &mut (impl ImageResource + ?Sized),
        offset: vk::Offset2D,
        extent: vk::Extent2D,
    ) {
        let de = dst.extent();
        assert!(
            offset.x >= 0
                && offset.y >= 0
                && offset.x as u64 + u64::from(extent.width) <= u64::from(de.width)
                && offset.y as u64 + u64::from(extent.height) <= u64::from(de.height),
            "a copy of {}×{} texels at ({}, {}) into an image of {}×{}",
            extent.width,
            extent.height,
            offset.x,
            offset.y,
            de.width,
            de.height
        );
        let texel = texel_bytes(dst.format()).unwrap_or_else(|| panic!("texel size of {:?}", dst.format()));
        let bytes = texel * u64::from(extent.width) * u64::from(extent.height);
        assert!(src.size_bytes() >= bytes, "`{}` holds fewer than the {bytes} bytes copied", src.name());
        if extent.width == 0 || extent.height == 0 {
            return;
        }
        self.declare_lifetime(src.lifetime(), Access::TRANSFER_READ);
        self.access_image(dst, Access::TRANSFER_WRITE, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        self.flush();
        let mut region = full_copy_region(dst.aspect(), extent);
        region.image_offset = vk::Offset3D { x: offset.x, y: offset.y, z: 0 };
        // SAFETY: the buffer is kept and large enough, the image live and in TRANSFER_DST, the
        // region inside it (checked above).
        unsafe {
            self.device().cmd_copy_buffer_to_image(
                self.cmd(),
                src.raw(),
                dst.handle(),
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Records a copy of the whole of `src` into `dst`, tightly packed. Panics if `dst` is
    /// smaller than the image's texels or the format's texel size is unknown.
    pub fn copy_image_to_buffer<T: Pod>(&mut self, src: &(impl ImageResource + ?Sized), dst: &Buffer<T>) {
        let e = src.extent();
        let texel = texel_bytes(src.format()).unwrap_or_else(|| panic!("texel size of {:?}", src.format()));
        let bytes = texel * u64::from(e.width) * u64::from(e.height);
        assert!(dst.size_bytes() >= bytes, "`{}` cannot hold the image's {bytes} bytes", dst.name());
        self.access_image(src, Access::TRANSFER_READ, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
        self.declare_lifetime(dst.lifetime(), Access::TRANSFER_WRITE);
        self.flush();
        let region = full_copy_region(src.aspect(), e);
        // SAFETY: the image is live and in TRANSFER_SRC; the buffer is kept and holds it.
        unsafe {
            self.device().cmd_copy_image_to_buffer(
                self.cmd(),
                src.handle(),
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.raw(),
                &[region],
            )
        };
    }

    /// Declares that commands recorded outside this recorder (a host's render pass, or
    /// [`Recorder::raw`] commands) left `image` in `layout`, last written as `written`.
    ///
    /// # Safety
    /// It is true when the next command recorded for `image` executes.
    pub unsafe fn image_written_externally(
        &mut self,
        image: &(impl ImageResource + ?Sized),
        layout: vk::ImageLayout,
        written: Access,
    ) {
        self.set_image_state(image, layout, super::access::State::written(written));
        if let Some(life) = image.tracking().life {
            self.keep_lifetime(life);
        }
    }

    /// Declares that a render pass of the engine left `image` in `layout`, its colour
    /// attachment writes visible to `visible` (its external subpass dependency).
    pub(crate) fn attachment_written(
        &mut self,
        image: &(impl ImageResource + ?Sized),
        layout: vk::ImageLayout,
        visible: vk::PipelineStageFlags2,
    ) {
        self.set_image_state(image, layout, super::access::State::attachment_written(visible));
    }

    /// What commands outside the recorder's sight left `image` as: its layout and state.
    fn set_image_state(
        &mut self,
        image: &(impl ImageResource + ?Sized),
        layout: vk::ImageLayout,
        state: super::access::State,
    ) {
        let t = image.tracking();
        *t.layout.lock().unwrap_or_else(|p| p.into_inner()) = layout;
        *self.state(t.key, t.life) = state;
    }
}
