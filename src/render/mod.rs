//! Rendering support shared by every renderer: offscreen render targets and readback, PNG and
//! EXR writers, colour maps as 1D textures, exposure tone mapping, a camera, and (feature `viewer`) the window.

mod camera;
mod colormap;
mod colormap_data;
mod draw;
mod draw_target;
mod error;
mod image_io;
mod phong;
mod target;
mod tonemap;
#[cfg(feature = "viewer")]
pub mod viewer;

/// Background of the engine's colour images and windows (linear RGBA, opaque dark grey).
pub const BACKGROUND: [f32; 4] = [0.12, 0.12, 0.14, 1.0];

pub use camera::{camera_for_box, Camera, Orbit};
pub use colormap::{ramp_coordinate, ramp_texcoord, Colormap, ColormapTexture, RAMP_TEXELS};
pub use draw::{check_pass, Draw};
pub use draw_target::DrawTarget;
pub use error::RenderError;
pub use image_io::{
    read_png_rgba8, rgba32f_channel, rgba8_channel, write_exr_channels, write_exr_rgba, write_png_rgba8,
};
pub use phong::{phong, PHONG_AMBIENT, PHONG_DIFFUSE, PHONG_SHININESS, PHONG_SPECULAR};
pub use target::{ColorFormat, Pixels, RenderTarget};
pub use tonemap::{auto_exposure, srgb_encode, tone_map};
