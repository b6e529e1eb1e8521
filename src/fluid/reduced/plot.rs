//! Fig. 5 (d) and (e) of seed 000 and the reduced-against-full comparisons as labelled PNG
//! plots (axes, units, legend), on the shared basics of [`crate::plot`].

use std::path::Path;

use plotters::prelude::*;

use crate::plot::{draw_legend, log_range, plot_err, save, SERIES};

use crate::fluid::FluidError;

use super::study::ErrorStudy;

/// Fig. 5 (d): the one-step error of every basis size over simulated time (log scale).
pub fn plot_over_time(study: &ErrorStudy, path: &Path) -> Result<(), FluidError> {
    crate::plot::font(path)?;
    let (w, h) = (1200u32, 700u32);
    let mut buf = vec![0u8; 3 * (w * h) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let t_end = study.sizes.iter().flat_map(|s| s.frames.last()).copied().max().unwrap_or(1) as f64
            * study.frame_time;
        let (lo, hi) = log_range(study.sizes.iter().flat_map(|s| s.errors.iter().copied()));
        let mut chart = ChartBuilder::on(&root)
            .caption("One-step error over the test run (seed 000 Fig. 5 d)", ("sans-serif", 28))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(90)
            .build_cartesian_2d(0.0..t_end.max(study.frame_time), (lo..hi).log_scale())
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc("simulated time (s)")
            .y_desc("one-step error E(u_ground − u_test) / E(u_ground)")
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 20))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        for (k, s) in study.sizes.iter().enumerate() {
            let colour = SERIES[k % SERIES.len()];
            let points: Vec<(f64, f64)> = s
                .frames
                .iter()
                .zip(&s.errors)
                .filter(|(_, e)| **e > 0.0)
                .map(|(f, e)| (*f as f64 * study.frame_time, *e))
                .collect();
            chart
                .draw_series(LineSeries::new(points, colour.stroke_width(2)))
                .map_err(|e| plot_err(path, e))?
                .label(format!("m = {}", s.m_u))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3)));
        }
        draw_legend(&mut chart, path)?;
        root.present().map_err(|e| plot_err(path, e))?;
    }
    Ok(save(path, w, h, &buf)?)
}

/// Fig. 5 (e): the time-integrated (mean) one-step error against the basis size (log–log).
pub fn plot_by_size(study: &ErrorStudy, path: &Path) -> Result<(), FluidError> {
    crate::plot::font(path)?;
    let (w, h) = (900u32, 650u32);
    let mut buf = vec![0u8; 3 * (w * h) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let points: Vec<(f64, f64)> =
            study.sizes.iter().map(|s| (s.m_u as f64, s.mean())).filter(|(_, e)| *e > 0.0).collect();
        let (lo, hi) = log_range(points.iter().map(|p| p.1));
        let (mlo, mhi) = log_range(points.iter().map(|p| p.0));
        let mut chart = ChartBuilder::on(&root)
            .caption("Time-integrated one-step error (seed 000 Fig. 5 e)", ("sans-serif", 26))
            .margin(20)
            .margin_right(45)
            .x_label_area_size(50)
            .y_label_area_size(90)
            .build_cartesian_2d((mlo..mhi).log_scale(), (lo..hi).log_scale())
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc("basis size m (m_u = m_f)")
            .y_desc("mean one-step error")
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 20))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        let colour = SERIES[0];
        chart
            .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
            .map_err(|e| plot_err(path, e))?
            .label("reduced model on the test run (not trained on)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3)));
        chart
            .draw_series(points.iter().map(|p| Circle::new(*p, 5, colour.filled())))
            .map_err(|e| plot_err(path, e))?;
        draw_legend(&mut chart, path)?;
        root.present().map_err(|e| plot_err(path, e))?;
    }
    Ok(save(path, w, h, &buf)?)
}

/// A comparison's kinetic energy over time, full and reduced runs (`energy_path`), and the
/// relative velocity error in the energy norm over time, log scale (`error_path`), with the
/// error indicator's estimate beside it when the comparison has one.
pub fn plot_comparison(
    c: &super::compare::Comparison,
    title: &str,
    energy_path: &Path,
    error_path: &Path,
) -> Result<(), FluidError> {
    crate::plot::font(energy_path)?;
    let (w, h) = (1100u32, 600u32);
    let t_end = (c.energy_full.len().saturating_sub(1)).max(1) as f64 * c.frame_time;
    let times = |v: &[f64]| -> Vec<(f64, f64)> {
        v.iter().enumerate().map(|(k, e)| (k as f64 * c.frame_time, *e)).collect()
    };
    // Energy.
    let mut buf = vec![0u8; 3 * (w * h) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(energy_path, e))?;
        let top = c.energy_full.iter().chain(&c.energy_reduced).fold(0.0f64, |m, v| m.max(*v)).max(1e-300);
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("Kinetic energy, full and reduced — {title}"), ("sans-serif", 26))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(90)
            .build_cartesian_2d(0.0..t_end, 0.0..1.1 * top)
            .map_err(|e| plot_err(energy_path, e))?;
        chart
            .configure_mesh()
            .x_desc("simulated time (s)")
            .y_desc("kinetic energy ½ Σ vol |u|²")
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 20))
            .y_label_formatter(&|v| format!("{v:.2e}"))
            .draw()
            .map_err(|e| plot_err(energy_path, e))?;
        for (k, (series, label)) in
            [(&c.energy_full, "full space"), (&c.energy_reduced, "reduced, lifted")].into_iter().enumerate()
        {
            let colour = SERIES[k];
            chart
                .draw_series(LineSeries::new(times(series), colour.stroke_width(2)))
                .map_err(|e| plot_err(energy_path, e))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3)));
        }
        draw_legend(&mut chart, energy_path)?;
        root.present().map_err(|e| plot_err(energy_path, e))?;
    }
    save(energy_path, w, h, &buf)?;
    // Error.
    let mut buf = vec![0u8; 3 * (w * h) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(error_path, e))?;
        let positive =
            |v: &[f64]| -> Vec<(f64, f64)> { times(v).into_iter().filter(|(_, e)| *e > 0.0).collect() };
        let (points, best, one, estimate) = (
            positive(&c.error),
            positive(&c.projection_error),
            positive(&c.one_step_error),
            positive(&c.estimate),
        );
        let (lo, hi) = log_range(points.iter().chain(&best).chain(&one).chain(&estimate).map(|p| p.1));
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("Velocity error of the reduced run — {title}"), ("sans-serif", 26))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(90)
            .build_cartesian_2d(0.0..t_end, (lo..hi).log_scale())
            .map_err(|e| plot_err(error_path, e))?;
        chart
            .configure_mesh()
            .x_desc("simulated time (s)")
            .y_desc("‖u_full − u‖_V / ‖u_full‖_V")
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 20))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| plot_err(error_path, e))?;
        let mut lines = vec![
            (SERIES[3], (points, "u = the reduced run, lifted")),
            (SERIES[2], (one, "u = one reduced step from the full run's previous frame")),
            (SERIES[1], (best, "u = the full run's best fit in B_u (truncation alone)")),
        ];
        if !estimate.is_empty() {
            lines.push((SERIES[0], (estimate, "the error indicator's estimate (without the full run)")));
        }
        for (colour, (series, label)) in lines {
            chart
                .draw_series(LineSeries::new(series, colour.stroke_width(2)))
                .map_err(|e| plot_err(error_path, e))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3)));
        }
        draw_legend(&mut chart, error_path)?;
        root.present().map_err(|e| plot_err(error_path, e))?;
    }
    Ok(save(error_path, w, h, &buf)?)
}

/// A rendered field picture (RGBA, `size`) with a title above it and a colour bar beside it:
/// the colour map `colormap` from `range.0` to `range.1`, its axis labelled `label`. For
/// pictures whose colours are a quantity (the comparison's error section).
pub fn plot_picture_with_colour_bar(
    rgba: &[u8],
    size: (u32, u32),
    colormap: &crate::render::Colormap,
    range: (f64, f64),
    (title, label): (&str, &str),
    path: &Path,
) -> Result<(), FluidError> {
    let bar = crate::plot::ColourBar { colormap, range, log: false, label, shift: 0.0 };
    Ok(crate::plot::picture_with_colour_bar(rgba, size, &bar, title, path)?)
}
