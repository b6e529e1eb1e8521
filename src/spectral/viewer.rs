//! Spectral elements in the interactive viewer (feature `viewer`), seed 002's "scale the data
//! to look at one region in detail" and "animated over time steps" made interactive. Keys:
//! space plays and pauses the time steps, `.` and `,` step; `l` log scale; `p` next palette;
//! `i` more iso-lines, `I` fewer; `e` element edges; `v` per-vertex colour; `h` height field
//! (planar meshes); `r` narrows the
//! colour range to its middle half, `R` restores it. Cut planes (hexahedral meshes): `n` adds
//! a plane (through the middle, the next axis), `c` selects the next plane, `j`/`k` move the
//! selected plane along its normal by 1/50 of the mesh, `o`/`O` turn its normal by 15° about
//! z, `u`/`U` tilt it by 15° towards z, `x` deletes it. Isosurfaces: `j`/`k` move the selected
//! value by 1/50 of the field's range, `c` selects the next, `n` adds one in the middle of the
//! range, `x` deletes it, `t` makes them transparent (opacity ½) and opaque again. Volumes: `k` more opaque, `j` less (the opacity unit distance ÷ or ×
//! 1.25). Surfaces, cut planes, isosurfaces and volumes orbit with the viewer's camera; planar
//! meshes stay fitted to the window.

use std::sync::Arc;

use anyhow::Result;

use super::{fit_camera, SpectralMesh, SpectralRenderer, SpectralView};
use crate::gpu::{Gpu, Recorder};
use crate::plot::ColourBar;
use crate::render::viewer::ViewerContent;
use crate::render::{Camera, Colormap, RenderTarget};

/// The palettes `p` cycles through.
const PALETTES: [&str; 3] = ["viridis", "cool-warm", "grey"];

/// The viewer's spectral content.
pub struct SpectralContent {
    mesh: Arc<SpectralMesh>,
    renderer: Option<SpectralRenderer>,
    gpu: Option<Gpu>,
    view: SpectralView,
    palette: usize,
    size: (u32, u32),
    playing: bool,
    /// Seconds per time step while playing.
    step_seconds: f64,
    clock: f64,
    frames: u64,
    /// The palette changed: swap the colour map in `update`, when no frame is in flight.
    recolour: bool,
    /// The colour map shown (for the legend).
    colormap: Colormap,
    /// The colour range of the step shown (for the legend), set in `update`.
    range: Option<(f64, f64)>,
    /// The selected cut plane.
    selected: usize,
    /// The mesh's bounding box: centre and size.
    centre: [f64; 3],
    extent: f64,
}

impl SpectralContent {
    /// Shows `mesh` as `view` in a `size` window with `palette` (a name of `PALETTES` or
    /// another map); `playing` starts stepping through time at once.
    pub fn new(
        mesh: Arc<SpectralMesh>,
        view: SpectralView,
        palette: &str,
        size: (u32, u32),
        playing: bool,
    ) -> Self {
        let palette = PALETTES.iter().position(|p| *p == palette).unwrap_or(0);
        let (lo, hi) = mesh.bounds();
        let centre: [f64; 3] = std::array::from_fn(|c| 0.5 * (lo[c] + hi[c]));
        let extent = (0..3).map(|c| hi[c] - lo[c]).fold(0.0, f64::max).max(1e-12);
        let mut view = view;
        if mesh.shape.is_volume() && view.cuts.is_empty() && view.iso.is_empty() && view.volume.is_none() {
            view.cuts.push([0.0, 0.0, 1.0, centre[2]]);
        }
        Self {
            mesh,
            renderer: None,
            gpu: None,
            view,
            palette,
            size,
            playing,
            step_seconds: 0.5,
            clock: 0.0,
            frames: 0,
            recolour: false,
            colormap: Colormap::viridis(),
            range: None,
            selected: 0,
            centre,
            extent,
        }
    }

    /// The time steps to cycle through: the shown field's, or with a derived field the fewest
    /// of the fields it reads.
    fn steps(&self) -> usize {
        let shown = self.mesh.fields[self.view.field].steps.len();
        match &self.view.expression {
            Some(d) => d
                .fields(self.view.field)
                .iter()
                .map(|&f| self.mesh.fields[f].steps.len())
                .fold(shown, usize::min),
            None => shown,
        }
        .max(1)
    }

    /// Turns the selected plane's normal by `angle` about z (`tilt`: towards z), keeping the
    /// point where it meets the normal line through the mesh's centre.
    fn turn(&mut self, angle: f64, tilt: bool) {
        let Some(c) = self.view.cuts.get_mut(self.selected) else { return };
        let len = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt().max(1e-300);
        let n = glam::DVec3::new(c[0], c[1], c[2]) / len;
        let centre = glam::DVec3::from(self.centre);
        let through = centre + (c[3] / len - n.dot(centre)) * n;
        let m = if tilt {
            let axis = n.cross(glam::DVec3::Z);
            if axis.length() < 1e-9 {
                glam::DMat3::from_rotation_x(angle)
            } else {
                glam::DMat3::from_axis_angle(axis.normalize(), angle)
            }
        } else {
            glam::DMat3::from_rotation_z(angle)
        };
        let n = m * n;
        *c = [n.x, n.y, n.z, n.dot(through)];
    }

    fn recolour(&mut self) -> Result<()> {
        if let (Some(gpu), Some(r)) = (&self.gpu, self.renderer.as_mut()) {
            self.colormap = Colormap::by_name(PALETTES[self.palette])?;
            r.set_colormap(gpu, &self.colormap)?;
        }
        Ok(())
    }
}

impl ViewerContent for SpectralContent {
    fn title(&self) -> String {
        let shown = super::picture::shown_label(&self.mesh, &self.view);
        let range =
            self.view.range.map_or("auto range".to_string(), |(lo, hi)| format!("[{lo:.3}, {hi:.3}]"));
        format!(
            "galerkin spectral — {} step {}/{} ({}) — {} {}, {}, {} iso-lines{}{}",
            shown,
            self.view.step,
            self.steps(),
            if self.playing { "playing" } else { "paused" },
            PALETTES[self.palette],
            if self.view.log { "log" } else { "linear" },
            range,
            self.view.isolines,
            if self.view.edges { ", edges" } else { "" },
            if self.view.per_vertex { ", per-vertex colour" } else { ", per-pixel colour" },
        ) + &if let Some(tf) = &self.view.volume {
            format!(" — volume, opacity unit distance {:.4}", tf.unit_distance)
        } else {
            String::new()
        } + &if !self.view.iso.is_empty() {
            let values: Vec<String> = self.view.iso.iter().map(|v| format!("{v:.4}")).collect();
            format!(
                " — isosurfaces {}, value {} selected{}",
                values.join(", "),
                self.selected.min(values.len() - 1),
                if self.view.uses_volume_pass() {
                    format!(", opacity {}", self.view.iso_opacity)
                } else {
                    String::new()
                }
            )
        } else if self.view.volume.is_some() || self.view.cuts.is_empty() {
            String::new()
        } else {
            let c = self.view.cuts[self.selected];
            format!(
                " — {} cut plane(s), plane {}: {:.2}x + {:.2}y + {:.2}z = {:.3}",
                self.view.cuts.len(),
                self.selected,
                c[0],
                c[1],
                c[2],
                c[3]
            )
        }
    }

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn camera(&self) -> Camera {
        self.view.camera.unwrap_or_else(|| fit_camera(&self.mesh))
    }

    fn start(&mut self, gpu: &Gpu, _: &RenderTarget) -> Result<()> {
        self.colormap = Colormap::by_name(PALETTES[self.palette])?;
        self.renderer = Some(SpectralRenderer::new(gpu, self.mesh.clone(), &self.colormap)?);
        self.gpu = Some(gpu.clone());
        Ok(())
    }

    fn update(&mut self, _: &RenderTarget, seconds: f64) -> Result<bool> {
        if std::mem::take(&mut self.recolour) {
            self.recolour()?;
        }
        if self.playing && self.frames > 0 {
            self.clock += seconds.min(0.1);
            while self.clock >= self.step_seconds {
                self.clock -= self.step_seconds;
                self.view.step = (self.view.step + 1) % self.steps();
            }
        }
        self.frames += 1;
        self.range = self.renderer.as_mut().map(|r| r.range(&self.view));
        Ok(self.playing)
    }

    fn legend(&self) -> Option<ColourBar<'_>> {
        let name = match &self.view.expression {
            Some(d) => d.expression.text.as_str(),
            None => self.mesh.fields[self.view.field].name.as_str(),
        };
        Some(super::picture::colour_bar(&self.colormap, self.range?, self.view.log, name))
    }

    fn record_prepass(
        &mut self,
        rec: &mut Recorder<'_>,
        target: &RenderTarget,
        camera: &Camera,
    ) -> Result<()> {
        if let Some(r) = self.renderer.as_mut() {
            let view = SpectralView { camera: Some(*camera), ..self.view.clone() };
            r.record_prepass(rec, target.draw_target(), &view)?;
        }
        Ok(())
    }

    fn record(&mut self, rec: &mut Recorder<'_>, target: &RenderTarget, camera: &Camera) -> Result<()> {
        if let Some(r) = self.renderer.as_mut() {
            let view = SpectralView { camera: Some(*camera), ..self.view.clone() };
            r.record_draw_into(rec, target.draw_target(), &view)?;
        }
        Ok(())
    }

    fn key(&mut self, key: &str) -> bool {
        let steps = self.steps();
        let iso = !self.view.iso.is_empty();
        match key {
            // Isosurfaces: the selected value moves by 1/50 of the field's range, within it.
            "j" | "k" if iso => {
                let (lo, hi) = self.mesh.value_range(self.view.field, self.view.step);
                let k = self.selected.min(self.view.iso.len() - 1);
                let moved = self.view.iso[k] + if key == "k" { 1.0 } else { -1.0 } * (hi - lo) / 50.0;
                self.view.iso[k] = moved.clamp(lo, hi);
            }
            "c" if iso => self.selected = (self.selected + 1) % self.view.iso.len(),
            "n" if iso && self.view.iso.len() < super::render::MAX_ISO_VALUES => {
                let (lo, hi) = self.mesh.value_range(self.view.field, self.view.step);
                self.view.iso.push(0.5 * (lo + hi));
                self.selected = self.view.iso.len() - 1;
            }
            // Transparent isosurfaces on (opacity ½) and off; drawn without edges.
            "t" if iso && self.view.volume.is_none() => {
                self.view.iso_opacity = if self.view.iso_opacity < 1.0 { 1.0 } else { 0.5 };
                self.view.edges &= !self.view.uses_volume_pass();
            }
            "x" if iso && self.view.iso.len() > 1 => {
                let k = self.selected.min(self.view.iso.len() - 1);
                self.view.iso.remove(k);
                self.selected = k.min(self.view.iso.len() - 1);
            }
            // A volume: more (k) or less (j) opaque, the unit distance divided or multiplied by
            // 1.25.
            "j" | "k" if self.view.volume.is_some() => {
                if let Some(tf) = self.view.volume.as_mut() {
                    tf.unit_distance *= if key == "k" { 0.8 } else { 1.25 };
                }
            }
            " " => self.playing = !self.playing,
            "." => self.view.step = (self.view.step + 1) % steps,
            "," => self.view.step = (self.view.step + steps - 1) % steps,
            "l" | "L" => self.view.log = !self.view.log,
            // A derived field is drawn per pixel and flat (refused otherwise): h and v do nothing.
            "h" | "H" if self.mesh.is_planar() && self.view.expression.is_none() => {
                self.view.height = if self.view.height.is_some() { None } else { Some(0.0) };
            }
            "i" => self.view.isolines += 2,
            "I" => self.view.isolines = self.view.isolines.saturating_sub(2),
            // Edges are not drawn on transparent isosurfaces or in a volume.
            "e" | "E" if !self.view.uses_volume_pass() => self.view.edges = !self.view.edges,
            "v" | "V" if self.view.expression.is_none() => self.view.per_vertex = !self.view.per_vertex,
            "r" => {
                let (lo, hi) = match (self.view.range, self.renderer.as_mut()) {
                    (Some(r), _) => r,
                    (None, Some(r)) => r.range(&self.view),
                    (None, None) => return false,
                };
                let q = 0.25 * (hi - lo);
                self.view.range = Some((lo + q, hi - q));
            }
            "R" => self.view.range = None,
            "n" if self.view.cuts.len() < super::render::MAX_CUT_PLANES => {
                let axis = self.view.cuts.len() % 3;
                let mut c = [0.0; 4];
                c[axis] = 1.0;
                c[3] = self.centre[axis];
                self.view.cuts.push(c);
                self.selected = self.view.cuts.len() - 1;
            }
            "c" if !self.view.cuts.is_empty() => self.selected = (self.selected + 1) % self.view.cuts.len(),
            "j" | "k" if self.selected < self.view.cuts.len() => {
                let c = &mut self.view.cuts[self.selected];
                let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                let moved = c[3] + if key == "k" { 1.0 } else { -1.0 } * self.extent / 50.0 * n;
                // The plane stops where it would leave the mesh.
                let (lo, hi) = super::render::plane_span(&self.mesh, [c[0], c[1], c[2], moved]);
                if (lo..=hi).contains(&(moved / n)) {
                    c[3] = moved;
                }
            }
            "o" => self.turn(15f64.to_radians(), false),
            "O" => self.turn(-15f64.to_radians(), false),
            "u" => self.turn(15f64.to_radians(), true),
            "U" => self.turn(-15f64.to_radians(), true),
            "x" if self.view.cuts.len() > 1 => {
                self.view.cuts.remove(self.selected);
                self.selected = self.selected.min(self.view.cuts.len() - 1);
            }
            "p" | "P" => {
                self.palette = (self.palette + 1) % PALETTES.len();
                self.recolour = true;
            }
            _ => return false,
        }
        true
    }

    fn summary(&self) -> Option<String> {
        Some(format!("viewer: {} frames, last time step {}", self.frames, self.view.step))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::generate::hex_shell;
    use crate::spectral::NodeSet;

    #[test]
    fn cut_plane_keys_move_turn_add_and_delete_planes() {
        let mesh = Arc::new(hex_shell(1, 2, 1, 2, 2, NodeSet::GaussLobatto).unwrap());
        let mut c = SpectralContent::new(mesh, SpectralView::default(), "viridis", (64, 64), false);
        assert_eq!(c.view.cuts, vec![[0.0, 0.0, 1.0, 0.5]], "a default plane through the middle");
        assert!(c.key("k"));
        assert!((c.view.cuts[0][3] - (0.5 + 1.0 / 50.0)).abs() < 1e-12, "moved by 1/50 of the mesh");
        assert!(c.key("n") && c.view.cuts.len() == 2 && c.selected == 1);
        // The new plane x = centre; turning it about z keeps its point on the centre line.
        let before = c.view.cuts[1];
        assert!(c.key("o"));
        let after = c.view.cuts[1];
        let angle = (before[0] * after[0] + before[1] * after[1]).acos();
        assert!((angle - 15f64.to_radians()).abs() < 1e-12);
        // The point where the old plane met the normal line through the centre.
        let through = [before[3], c.centre[1], c.centre[2]];
        let d = after[0] * through[0] + after[1] * through[1] + after[2] * through[2];
        assert!((d - after[3]).abs() < 1e-12, "kept its point: {d} vs {}", after[3]);
        assert!(c.key("x") && c.view.cuts.len() == 1 && c.selected == 0);
        assert!(!c.key("x"), "the last plane stays");
        // Moving a plane stops where it would leave the mesh (the renderer refuses such a plane).
        for _ in 0..200 {
            c.key("k");
        }
        let (_, hi) = crate::spectral::render::plane_span(&c.mesh, c.view.cuts[0]);
        assert!(
            c.view.cuts[0][3] <= hi && c.view.cuts[0][3] > hi - 2.0 / 50.0,
            "{:?} within {hi}",
            c.view.cuts[0]
        );
    }

    #[test]
    fn iso_and_volume_keys_move_values_and_opacity() {
        let mesh = Arc::new(hex_shell(1, 2, 1, 2, 2, NodeSet::GaussLobatto).unwrap());
        let (lo, hi) = mesh.value_range(0, 0);
        let view = SpectralView { iso: vec![0.5 * (lo + hi)], ..SpectralView::default() };
        let mut c = SpectralContent::new(mesh.clone(), view, "viridis", (64, 64), false);
        assert!(c.view.cuts.is_empty(), "no cut plane is added to an isosurface view");
        assert!(c.key("k"));
        assert!((c.view.iso[0] - (0.5 * (lo + hi) + (hi - lo) / 50.0)).abs() < 1e-12);
        assert!(c.key("n") && c.view.iso.len() == 2 && c.selected == 1);
        for _ in 0..100 {
            c.key("j");
        }
        assert_eq!(c.view.iso[1], lo, "a value stops at the bottom of the range");
        assert!(c.key("x") && c.view.iso.len() == 1 && c.selected == 0);
        assert!(!c.key("x"), "the last value stays");
        assert!(c.title().contains("isosurfaces"), "{}", c.title());
        // t: transparent (drawn by the volume pass, edges off) and opaque again.
        assert!(c.key("e") && c.view.edges);
        assert!(c.key("t") && c.view.iso_opacity == 0.5 && c.view.uses_volume_pass() && !c.view.edges);
        assert!(c.title().contains("opacity 0.5"), "{}", c.title());
        assert!(!c.key("e") && !c.view.edges, "no edges on transparent isosurfaces");
        assert!(c.key("t") && c.view.iso_opacity == 1.0 && !c.view.uses_volume_pass());
        let tf = crate::spectral::transfer::TransferFunction::new(vec![(lo, 0.0), (hi, 0.5)], 1.0).unwrap();
        let mut v = SpectralContent::new(
            mesh,
            SpectralView { volume: Some(tf), ..SpectralView::default() },
            "viridis",
            (64, 64),
            false,
        );
        assert!(v.view.cuts.is_empty(), "no cut plane is added to a volume view");
        assert!(v.key("k") && v.key("k"));
        let unit = v.view.volume.as_ref().map(|t| t.unit_distance);
        assert!(unit.is_some_and(|u| (u - 0.64).abs() < 1e-12), "{unit:?}");
        assert!(v.title().contains("unit distance 0.64"), "{}", v.title());
    }
}
