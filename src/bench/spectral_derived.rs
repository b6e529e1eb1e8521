//! `galerkin spectral bench --derived`: what a derived field (`--expr`) costs — the run-time
//! compilation of its fragment shader, and its device frame time against the field itself on
//! the same view, interleaved frame by frame — with the CPU path beside it: the f64
//! interpreter evaluating the same expression at every covered pixel (the reference the tests
//! use), on the same image.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Result};

use crate::expression::spectral::{DerivedField, DerivedShader};
use crate::gpu::Gpu;
use crate::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use crate::spectral::{generate, NodeSet, Shape, SpectralMesh, SpectralRenderer, SpectralView};

/// A benchmark case: generated data set, order, image size, expressions.
type Case = (&'static str, usize, (u32, u32), &'static [&'static str]);

fn median(mut v: Vec<f64>) -> f64 {
    crate::bench::median_f64(&mut v)
}

/// The CPU path: the derived field in f64 at the reference point each covered pixel of a data
/// image reports (so both paths evaluate the same points; the pull-back is not timed). Wall
/// time in ms, on all cores.
fn cpu_ms(mesh: &SpectralMesh, d: &DerivedField, pixels: &[f32]) -> f64 {
    use rayon::prelude::*;
    let start = Instant::now();
    let sum: f64 = pixels
        .par_chunks_exact(4)
        .filter(|t| t[3] >= 0.0)
        .map(|t| {
            let e = t[3] as usize;
            match mesh.shape {
                Shape::Quadrilateral | Shape::Triangle => {
                    d.value_at(mesh, 0, 0, e, [f64::from(t[1]), f64::from(t[2])])
                }
                // Cut planes report (value, plane, ζ, element): ξ and η are not in the image;
                // the cell centre stands in (the same cost per point).
                Shape::Hexahedron | Shape::Tetrahedron => {
                    d.value_at_hex(mesh, 0, 0, e, [0.5, 0.5, f64::from(t[2])])
                }
            }
        })
        .filter(|v| v.is_finite())
        .sum();
    std::hint::black_box(sum);
    start.elapsed().as_secs_f64() * 1e3
}

/// The derived-field table on `gpu` as Markdown through `emit`: per data set and expression,
/// the shader's compile time (shaderc, wall), the median device time of `frames` frames of the
/// field itself and of the derived field (interleaved), and the CPU interpreter's time for
/// the same pixels.
pub fn report(gpu: &Gpu, frames: usize, emit: &mut dyn FnMut(&str)) -> Result<()> {
    macro_rules! say {
        ($($t:tt)*) => { emit(&format!("{}\n", format_args!($($t)*))) };
    }
    let frames = frames.max(1);
    let c = gpu.caps();
    say!(
        "Device: {} ({}); median device time of {frames} frames, the field and the derived field interleaved frame by frame; compile: shaderc from source text to SPIR-V (wall, once per expression); CPU: the f64 interpreter at every covered pixel's reference point (all cores, wall).\n",
        c.device_name, c.driver
    );
    say!("| data | size | expression | compile ms | field ms | derived ms | derived ÷ field | pixels | CPU ms | CPU ÷ derived |");
    say!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|");
    let mut profiler = crate::gpu::Profiler::new(gpu, 1)?;
    let colormap = Colormap::viridis();
    let cases: [Case; 3] = [
        ("annulus", 8, (1920, 1080), &["u", "length(grad(u))", "dot(grad(u), grad(cells)) / (1 + u * u)"]),
        ("artery", 5, (1024, 768), &["u", "length(grad(u))"]),
        ("shell", 4, (1024, 768), &["u", "length(grad(u))"]),
    ];
    for (name, order, (w, h), expressions) in cases {
        let mesh = Arc::new(generate::by_name(name, 3, order, NodeSet::GaussLobatto)?);
        let mut renderer = SpectralRenderer::new(gpu, mesh.clone(), &colormap)?;
        let target = RenderTarget::new(gpu, "bench derived", w, h, ColorFormat::Rgba8)?;
        let data = RenderTarget::new(gpu, "bench derived data", w, h, ColorFormat::Rgba32F)?;
        let kind = match (mesh.shape, mesh.is_planar()) {
            (Shape::Hexahedron | Shape::Tetrahedron, _) => DerivedShader::CutPlanes,
            (_, true) => DerivedShader::Planar,
            _ => DerivedShader::Surface,
        };
        let plain = SpectralView { overdraw: false, ..SpectralView::default() };
        for text in expressions {
            let d = Arc::new(DerivedField::new(&mesh, text)?);
            let start = Instant::now();
            d.compile_fragment(kind, mesh.elements())?;
            let compile_ms = start.elapsed().as_secs_f64() * 1e3;
            let derived = SpectralView { expression: Some(d.clone()), ..plain.clone() };
            let (f, dv) = super::spectral::interleaved_medians(
                &mut renderer,
                &target,
                [&plain, &derived],
                frames,
                2,
                &mut profiler,
            )?;
            let Pixels::Rgba32F(pixels) = renderer.render(&data, &derived)? else {
                bail!("a float target returned bytes")
            };
            let covered = pixels.chunks_exact(4).filter(|t| t[3] >= 0.0).count();
            let cpu = median((0..3).map(|_| cpu_ms(&mesh, &d, &pixels)).collect());
            say!(
                "| {name} ({} elements, order {order}) | {w}×{h} | `{text}` | {compile_ms:.0} | {f:.1} | {dv:.1} | {:.2}× | {covered} | {cpu:.0} | {:.2}× |",
                mesh.elements(),
                dv / f,
                cpu / dv
            );
        }
    }
    Ok(())
}
