//! The interactive window (feature `viewer`): winit + an ash-window surface + a swapchain.
//! Each frame renders the content ([`ViewerContent`], which each capability implements: the
//! demo scene in `crate::demo::viewer`, a spacetime slice, spectral elements, …)
//! offscreen with the same render pass and pipelines as the offscreen commands, then blits it
//! into the acquired swapchain image, so the window shows exactly what the PNG would hold. Esc
//! quits, S saves a screenshot (copied back from the presented swapchain image), arrow keys
//! orbit the camera, +/- zoom; other keys go to the content. Resizing recreates the swapchain
//! and the offscreen target. winit allows one event loop per process, so tests run the
//! `galerkin` binary as a child under Xvfb.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{anyhow, Context, Result};
use ash::vk;
use glam::DVec3;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

use super::{write_png_rgba8, Camera, ColorFormat, RenderTarget};
use crate::gpu::{
    surface_extensions, Access, Buffer, ForeignImage, Gpu, GpuDesc, MemoryKind, Recorder, Submission,
    Surface, Swapchain,
};
use crate::plot::{colour_bar_rgba, ColourBar, BAR_WIDTH};

/// What the viewer shows. The viewer owns the window, the swapchain, the offscreen target and
/// the camera; the content draws into the target's render pass.
pub trait ViewerContent {
    /// The window's title (asked again after every frame: it may show state, e.g. the time).
    fn title(&self) -> String;
    /// The window's initial size.
    fn size(&self) -> (u32, u32);
    /// The initial camera.
    fn camera(&self) -> Camera;
    /// Creates the device objects, once the device and the first target exist.
    fn start(&mut self, gpu: &Gpu, target: &RenderTarget) -> Result<()>;
    /// Work before a frame is recorded (it may submit its own work, e.g. a compute pass), with
    /// the seconds since the last frame. Returns true while animating (another frame is wanted).
    fn update(&mut self, target: &RenderTarget, seconds: f64) -> Result<bool>;
    /// Records work the frame needs before its render pass (e.g. a compute pass that builds
    /// what `record` draws). Default: none.
    fn record_prepass(
        &mut self,
        _rec: &mut Recorder<'_>,
        _target: &RenderTarget,
        _camera: &Camera,
    ) -> Result<()> {
        Ok(())
    }
    /// Records the frame's draws inside the target's render pass.
    fn record(&mut self, rec: &mut Recorder<'_>, target: &RenderTarget, camera: &Camera) -> Result<()>;
    /// A key the viewer does not use (a character, or " " for the space bar); true if it
    /// changed what is shown.
    fn key(&mut self, key: &str) -> bool;
    /// A line for the terminal when the viewer closes (e.g. where an animation stopped).
    fn summary(&self) -> Option<String> {
        None
    }
    /// What the picture's colours mean, shown as a colour bar beside it (the one the PNG
    /// pictures carry) when the window is wide enough. Default: none.
    fn legend(&self) -> Option<ColourBar<'_>> {
        None
    }
}

/// The narrowest window that shows the legend: the picture keeps at least two thirds.
pub const LEGEND_MIN_WIDTH: u32 = 3 * BAR_WIDTH;

/// The colour bar beside the picture: drawn on the CPU by [`colour_bar_rgba`] (as the PNG
/// legend is) when what it shows or the window's height changes, kept in the swapchain's byte
/// order and copied into the right-hand strip of each presented image.
struct LegendStrip {
    /// What it shows (range, scale, label, map, height).
    key: String,
    /// [`BAR_WIDTH`] × `height` texels in the swapchain's byte order.
    texels: Buffer<u8>,
    height: u32,
}

/// How a viewer run goes: interactive by default, scripted for tests and recordings.
#[derive(Clone, Debug, Default)]
pub struct ViewOptions {
    /// Quit after this many presented frames, saving the screenshot from the last one.
    pub frames: Option<u64>,
    /// Where S (and a scripted run's last frame) saves the screenshot.
    pub screenshot: PathBuf,
    /// In a scripted run, ask for this window size (width, height) halfway through.
    pub resize_to: Option<(u32, u32)>,
    /// In a scripted run, keys given to the content as if pressed: `(frame, key)`, each before
    /// that many frames have been presented ([`ScriptedKeys`]).
    pub keys: Vec<(u64, String)>,
}

/// Keys pressed at frames, written `KEY@FRAME` comma-separated (`1@3,3@20, @40`: a space
/// is the space bar), for scripted viewer runs and their tests.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScriptedKeys(pub Vec<(u64, String)>);

impl std::str::FromStr for ScriptedKeys {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let mut keys = Vec::new();
        for part in s.split(',').filter(|p| !p.is_empty()) {
            let (key, frame) =
                part.rsplit_once('@').ok_or_else(|| format!("`{part}`: expected KEY@FRAME"))?;
            if key.chars().count() != 1 {
                return Err(format!("`{part}`: a key is one character"));
            }
            let frame: u64 = frame.parse().map_err(|e| format!("`{part}`: frame: {e}"))?;
            keys.push((frame, key.to_string()));
        }
        if keys.len() > 10_000 {
            return Err(format!("{} scripted keys: at most 10,000", keys.len()));
        }
        keys.sort_by_key(|k| k.0);
        Ok(Self(keys))
    }
}

/// Opens the window on `content` and runs until Esc, the window closes, or `options.frames`
/// frames have been presented.
pub fn run(desc: GpuDesc, content: Box<dyn ViewerContent>, options: ViewOptions) -> Result<()> {
    let ViewOptions { frames, screenshot, resize_to, keys } = options;
    let event_loop = EventLoop::new().context("cannot open a window (is DISPLAY or WAYLAND_DISPLAY set?)")?;
    let mut app = App {
        desc,
        content: Some(content),
        frames,
        screenshot,
        resize_to,
        state: None,
        error: None,
        presented: 0,
        save_next: false,
        keys,
    };
    event_loop.run_app(&mut app).context("window event loop")?;
    match app.error {
        Some(e) => Err(e),
        None => {
            if let Some(state) = app.state.take() {
                if let Some(line) = state.content.summary() {
                    println!("{line}");
                }
                state.finish()?;
            }
            Ok(())
        }
    }
}

struct App {
    desc: GpuDesc,
    content: Option<Box<dyn ViewerContent>>,
    frames: Option<u64>,
    screenshot: PathBuf,
    resize_to: Option<(u32, u32)>,
    state: Option<State>,
    error: Option<anyhow::Error>,
    presented: u64,
    /// Scripted keys not yet given, in frame order.
    keys: Vec<(u64, String)>,
    save_next: bool,
}

/// Everything that lives while the window is open. Field order is drop order: the last frame
/// is waited on first, then the swapchain goes before its surface, the window last.
struct State {
    last_frame: Option<Submission>,
    content: Box<dyn ViewerContent>,
    last_update: Instant,
    animating: bool,
    target: RenderTarget,
    readback: Option<Buffer<u8>>,
    legend: Option<LegendStrip>,
    /// What the legend could not be drawn for (said once; tried again when it changes).
    legend_failed: Option<String>,
    swapchain: Option<Swapchain>,
    surface: Surface,
    gpu: Gpu,
    camera: Camera,
    window: Window,
}

impl State {
    fn new(
        event_loop: &ActiveEventLoop,
        desc: &GpuDesc,
        mut content: Box<dyn ViewerContent>,
    ) -> Result<Self> {
        let (width, height) = content.size();
        let attrs = Window::default_attributes()
            .with_title(content.title())
            .with_inner_size(winit::dpi::PhysicalSize::new(width, height));
        let window = event_loop.create_window(attrs).context("create window")?;
        let display = window.display_handle().map_err(|e| anyhow!("display handle: {e}"))?.as_raw();
        let handle = window.window_handle().map_err(|e| anyhow!("window handle: {e}"))?.as_raw();
        let mut desc = desc.clone();
        desc.instance_extensions.extend(surface_extensions(display)?);
        desc.swapchain = true;
        let gpu = Gpu::new(&desc)?;
        // SAFETY: the handles come from `window`, which outlives the surface (field order).
        let surface = unsafe { Surface::new(&gpu, display, handle) }?;
        let size = window.inner_size();
        let swapchain = Swapchain::new(&gpu, &surface, size.width.max(1), size.height.max(1), None)?;
        let extent = swapchain.extent();
        let target =
            RenderTarget::new(&gpu, "viewer frame", extent.width, extent.height, ColorFormat::Rgba8)?;
        content.start(&gpu, &target)?;
        Ok(Self {
            last_frame: None,
            camera: content.camera(),
            content,
            last_update: Instant::now(),
            animating: false,
            target,
            readback: None,
            legend: None,
            legend_failed: None,
            swapchain: Some(swapchain),
            surface,
            gpu,
            window,
        })
    }

    fn wait_last_frame(&mut self) -> Result<()> {
        if let Some(f) = self.last_frame.take() {
            f.wait()?;
        }
        Ok(())
    }

    fn recreate(&mut self) -> Result<()> {
        self.wait_last_frame()?;
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(()); // minimised: keep the old one until there is something to show
        }
        let old = self.swapchain.take();
        let swapchain = Swapchain::new(&self.gpu, &self.surface, size.width, size.height, old.as_ref())?;
        // The last present may still wait on the old swapchain's semaphores: the frame's fence
        // does not cover presentation.
        self.gpu.wait_queue_idle()?;
        drop(old);
        // The frame fits the offscreen target to the new extent (less the legend's strip).
        self.swapchain = Some(swapchain);
        Ok(())
    }

    /// Renders and presents one frame; with `save`, also copies the presented image back.
    /// Returns false if the swapchain had to be recreated instead.
    fn frame(&mut self, save: bool) -> Result<bool> {
        self.wait_last_frame()?;
        let now = Instant::now();
        let seconds = now.duration_since(self.last_update).as_secs_f64();
        self.last_update = now;
        self.animating = self.content.update(&self.target, seconds)?;
        let Some(swapchain) = self.swapchain.as_ref() else {
            return Ok(false);
        };
        let Some(index) = swapchain.acquire()? else {
            self.recreate()?;
            return Ok(false);
        };
        let image = swapchain.images()[index as usize];
        let extent = swapchain.extent();
        let format = swapchain.format();
        self.update_legend(format, extent)?;
        let bar = if self.legend.is_some() { BAR_WIDTH } else { 0 };
        let picture = vk::Extent2D { width: extent.width - bar, height: extent.height };
        if self.target.extent() != picture {
            // Same formats, so the render pass is compatible and the pipelines can stay.
            self.target = RenderTarget::new(
                &self.gpu,
                "viewer frame",
                picture.width,
                picture.height,
                ColorFormat::Rgba8,
            )?;
        }
        let swapchain = self.swapchain.as_ref().expect("present above");
        let readable = save && swapchain.readable();
        if readable {
            let bytes = 4 * u64::from(extent.width) * u64::from(extent.height);
            self.readback = Some(Buffer::new(
                &self.gpu,
                "screenshot",
                bytes,
                vk::BufferUsageFlags::empty(),
                MemoryKind::GpuToCpu,
            )?);
        }
        let (gpu, target, content, camera, readback, legend) =
            (&self.gpu, &self.target, &mut self.content, &self.camera, &self.readback, &self.legend);
        let waits = [(swapchain.image_available, vk::PipelineStageFlags::TRANSFER)];
        let signals = [swapchain.render_finished[index as usize]];
        let record = |rec: &mut Recorder<'_>| {
            let prepared = content.record_prepass(rec, target, camera);
            target.record_begin(rec, crate::render::BACKGROUND);
            let recorded = prepared.and_then(|()| content.record(rec, target, camera));
            target.record_end(rec);
            target.keep(rec);
            // SAFETY: the swapchain image is a live colour image of this device with one level
            // and layer, in the swapchain's format and extent, made with transfer-destination
            // (and, when readable, transfer-source) usage; it stays alive until the swapchain is
            // recreated, which waits for this frame's submission first. Its contents are not
            // kept (UNDEFINED).
            let mut screen = unsafe { ForeignImage::new(image, format, extent, vk::ImageLayout::UNDEFINED) };
            // The acquire's semaphore is waited for at the transfer stage: the layout change
            // must come after it.
            let acquired =
                Access { stages: vk::PipelineStageFlags2::TRANSFER, access: vk::AccessFlags2::empty() };
            // SAFETY: the submission waits for `image_available` at TRANSFER before this.
            unsafe { rec.image_written_externally(&screen, vk::ImageLayout::UNDEFINED, acquired) };
            rec.blit(target.color_image(), &mut screen, picture);
            if let Some(strip) = legend {
                let at = vk::Offset2D { x: picture.width as i32, y: 0 };
                let size = vk::Extent2D { width: BAR_WIDTH, height: strip.height };
                rec.copy_buffer_to_image(&strip.texels, &mut screen, at, size);
            }
            if let (true, Some(buf)) = (readable, readback) {
                rec.copy_image_to_buffer(&screen, buf);
                rec.access(buf, Access::HOST_READ);
            }
            let present =
                Access { stages: vk::PipelineStageFlags2::empty(), access: vk::AccessFlags2::empty() };
            rec.transition(&mut screen, vk::ImageLayout::PRESENT_SRC_KHR, present);
            recorded
        };
        // SAFETY: the swapchain's semaphores are live until the swapchain is recreated, which
        // waits for this frame first; `image_available` was handed to the acquire of `index`,
        // and this image's `render_finished` was waited on by its last presentation.
        let frame = unsafe { gpu.submit_with_semaphores(&waits, &signals, record) };
        let (submission, recorded) = frame?;
        self.last_frame = Some(submission);
        recorded?;
        let fresh = swapchain.present(index)?;
        if readable {
            self.wait_last_frame()?;
        }
        if !fresh {
            self.recreate()?;
        }
        Ok(true)
    }

    /// Draws the content's legend for a window of `extent` in `format` when what it shows has
    /// changed (no frame is in flight: the last one was waited for). None when the content has
    /// none, the window is narrower than [`LEGEND_MIN_WIDTH`], the swapchain's format is not
    /// 8-bit RGBA or BGRA, or the legend cannot be drawn (no font, a log range reaching 0: said
    /// once for each thing it would show).
    fn update_legend(&mut self, format: vk::Format, extent: vk::Extent2D) -> Result<()> {
        let bgra = match format {
            vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB => true,
            vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB => false,
            _ => {
                self.legend = None;
                return Ok(());
            }
        };
        let bar = match self.content.legend() {
            Some(bar) if extent.width >= LEGEND_MIN_WIDTH && extent.height > 0 => bar,
            _ => {
                self.legend = None;
                return Ok(());
            }
        };
        let key = format!(
            "{:?} {} {} {} {} {}",
            bar.range,
            bar.log,
            bar.label,
            bar.shift,
            bar.colormap.name(),
            extent.height
        );
        if self.legend.as_ref().is_some_and(|l| l.key == key) || self.legend_failed.as_ref() == Some(&key) {
            return Ok(());
        }
        let mut rgba = match colour_bar_rgba(&bar, extent.height, std::path::Path::new("the viewer's legend"))
        {
            Ok(rgba) => rgba,
            Err(e) => {
                eprintln!("warning: {e}; the viewer shows no legend");
                self.legend_failed = Some(key);
                self.legend = None;
                return Ok(());
            }
        };
        if bgra {
            for p in rgba.chunks_exact_mut(4) {
                p.swap(0, 2);
            }
        }
        let mut texels = Buffer::new(
            &self.gpu,
            "viewer legend",
            rgba.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryKind::CpuToGpu,
        )?;
        texels.mapped_mut()?.copy_from_slice(&rgba);
        self.legend = Some(LegendStrip { key, texels, height: extent.height });
        Ok(())
    }

    /// Writes the last frame's copy of the presented image as PNG (RGBA; BGRA swapchains
    /// are swizzled). Falls back to the offscreen frame if the swapchain is not readable.
    fn save_screenshot(&mut self, path: &std::path::Path) -> Result<()> {
        self.wait_last_frame()?;
        let (format, extent) = match &self.swapchain {
            Some(s) => (s.format(), s.extent()),
            None => return Ok(()),
        };
        let mut rgba = match self.readback.take() {
            Some(buf) => buf.mapped().map(<[u8]>::to_vec).unwrap_or_default(),
            None => match self.target.readback(&self.gpu)? {
                super::Pixels::Rgba8(p) => p,
                super::Pixels::Rgba32F(_) => unreachable!("viewer target is RGBA8"),
            },
        };
        let (w, h) = if rgba.len() as u64 == 4 * u64::from(extent.width) * u64::from(extent.height) {
            (extent.width, extent.height)
        } else {
            (self.target.extent().width, self.target.extent().height)
        };
        if matches!(format, vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB) {
            for p in rgba.chunks_exact_mut(4) {
                p.swap(0, 2);
            }
        }
        write_png_rgba8(path, w, h, &rgba)?;
        eprintln!("saved {} ({w}×{h})", path.display());
        Ok(())
    }

    fn orbit(&mut self, yaw: f64, pitch: f64, zoom: f64) {
        let target = DVec3::from(self.camera.target);
        let up = DVec3::from(self.camera.up).normalize();
        let mut offset = DVec3::from(self.camera.eye) - target;
        offset = glam::DQuat::from_axis_angle(up, yaw) * offset;
        let right = offset.cross(up);
        if right.length() > 1e-9 {
            let pitched = glam::DQuat::from_axis_angle(right.normalize(), pitch) * offset;
            if pitched.normalize().dot(up).abs() < 0.995 {
                offset = pitched;
            }
        }
        self.camera.eye = (target + offset * zoom).to_array();
    }

    fn finish(mut self) -> Result<()> {
        self.wait_last_frame()?;
        // The last present too, before the swapchain's semaphores go.
        self.gpu.wait_queue_idle()?;
        let log = self.gpu.validation_log();
        drop(self);
        if let Some(errors) = log.map(|l| l.errors()).filter(|e| !e.is_empty()) {
            return Err(anyhow!("{} Vulkan validation error(s); the first: {}", errors.len(), errors[0]));
        }
        Ok(())
    }
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error = Some(e);
        event_loop.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        let Some(content) = self.content.take() else {
            return;
        };
        match State::new(event_loop, &self.desc, content) {
            Ok(s) => {
                s.window.request_redraw();
                self.state = Some(s);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(state) = self.state.as_mut() else {
            return;
        };
        let result: Result<()> = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(_) => state.recreate(),
            WindowEvent::KeyboardInput {
                event: KeyEvent { logical_key, state: ElementState::Pressed, .. },
                ..
            } => {
                let step = 5f64.to_radians();
                match logical_key.as_ref() {
                    Key::Named(NamedKey::Escape) => event_loop.exit(),
                    Key::Named(NamedKey::ArrowLeft) => state.orbit(-step, 0.0, 1.0),
                    Key::Named(NamedKey::ArrowRight) => state.orbit(step, 0.0, 1.0),
                    Key::Named(NamedKey::ArrowUp) => state.orbit(0.0, step, 1.0),
                    Key::Named(NamedKey::ArrowDown) => state.orbit(0.0, -step, 1.0),
                    Key::Character("+") | Key::Character("=") => state.orbit(0.0, 0.0, 0.9),
                    Key::Character("-") => state.orbit(0.0, 0.0, 1.0 / 0.9),
                    Key::Character(c) if c.eq_ignore_ascii_case("s") => self.save_next = true,
                    Key::Named(NamedKey::Space) => {
                        state.content.key(" ");
                    }
                    Key::Character(c) => {
                        state.content.key(c);
                    }
                    _ => {}
                }
                state.window.request_redraw();
                Ok(())
            }
            WindowEvent::RedrawRequested => {
                while self.keys.first().is_some_and(|(frame, _)| *frame <= self.presented) {
                    let (_, key) = self.keys.remove(0);
                    state.content.key(&key);
                }
                let save = self.save_next || self.frames.is_some_and(|n| self.presented + 1 >= n);
                match state.frame(save) {
                    Ok(true) => {
                        self.presented += 1;
                        let mut r = Ok(());
                        if save {
                            self.save_next = false;
                            r = state.save_screenshot(&self.screenshot);
                        }
                        if let (Some(n), Some((w, h))) = (self.frames, self.resize_to) {
                            if self.presented == n / 2 {
                                let _ = state.window.request_inner_size(winit::dpi::PhysicalSize::new(w, h));
                            }
                        }
                        state.window.set_title(&state.content.title());
                        if self.frames.is_some_and(|n| self.presented >= n) {
                            event_loop.exit();
                        } else if self.frames.is_some() || state.animating {
                            state.window.request_redraw();
                        }
                        r
                    }
                    Ok(false) => {
                        state.window.request_redraw();
                        Ok(())
                    }
                    Err(e) => Err(e),
                }
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }
}
