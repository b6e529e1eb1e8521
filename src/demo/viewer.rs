//! The demo scene in the viewer: [`DemoContent`] is the [`ViewerContent`] of `galerkin demo`
//! (the viewer takes content through that trait and knows nothing of the demo).

use anyhow::Result;

use super::field::{FieldOutput, FieldPass};
use super::scene::DemoScene;
use crate::gpu::{Gpu, Recorder};
use crate::render::viewer::ViewerContent;
use crate::render::{Camera, Colormap, RenderTarget};

/// The demo scene of `galerkin demo` (one polynomial, per-pixel colour).
pub struct DemoContent {
    scene: DemoScene,
    pass: Option<FieldPass>,
}

impl DemoContent {
    /// The content of `scene`.
    pub fn new(scene: DemoScene) -> Self {
        Self { scene, pass: None }
    }
}

impl ViewerContent for DemoContent {
    fn title(&self) -> String {
        "galerkin".into()
    }

    fn size(&self) -> (u32, u32) {
        (self.scene.image.width, self.scene.image.height)
    }

    fn camera(&self) -> Camera {
        self.scene.camera
    }

    fn start(&mut self, gpu: &Gpu, target: &RenderTarget) -> Result<()> {
        let colormap = Colormap::by_name(&self.scene.colormap_name())?;
        self.pass = Some(FieldPass::new(
            gpu,
            target.render_pass(),
            &self.scene.field.coefficients,
            self.scene.field.tessellation,
            &colormap,
            self.scene.ramp(),
            FieldOutput::Colour,
        )?);
        Ok(())
    }

    fn update(&mut self, _: &RenderTarget, _: f64) -> Result<bool> {
        Ok(false)
    }

    fn record(&mut self, rec: &mut Recorder<'_>, target: &RenderTarget, camera: &Camera) -> Result<()> {
        if let Some(pass) = &self.pass {
            pass.record(rec, target.extent(), camera);
        }
        Ok(())
    }

    fn key(&mut self, _: &str) -> bool {
        false
    }
}
