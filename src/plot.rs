//! Labelled PNG plots (axes with units, ticks, a legend, a title), drawn by the `plotters`
//! crate into a pixel buffer and written by our PNG writer: the shared basics of every plot
//! the engine writes (the fluid error studies and comparisons, `radiosity compare`). Text uses
//! the DejaVu Sans TrueType font from the system (Debian's fonts-dejavu-core).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

/// A plot that could not be drawn or written: the file and why.
#[derive(Debug, thiserror::Error)]
#[error("{path}: plot: {message}")]
pub struct PlotError {
    /// The plot's file.
    pub path: PathBuf,
    /// What went wrong.
    pub message: String,
}

/// A [`PlotError`] for `path`.
pub fn plot_err(path: &Path, e: impl std::fmt::Display) -> PlotError {
    PlotError { path: path.to_path_buf(), message: e.to_string() }
}

/// Where the plots' font is read from.
pub const FONT_PATHS: [&str; 2] =
    ["/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", "/usr/share/fonts/dejavu/DejaVuSans.ttf"];

static FONT: OnceLock<Result<(), String>> = OnceLock::new();

/// Registers the font as "sans-serif" (once); refused, naming the paths tried, if none is there.
pub fn font(path: &Path) -> Result<(), PlotError> {
    FONT.get_or_init(|| {
        for p in FONT_PATHS {
            if let Ok(bytes) = std::fs::read(p) {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                return register_font("sans-serif", FontStyle::Normal, bytes)
                    .map_err(|_| format!("{p}: not a usable TrueType font"));
            }
        }
        Err(format!("no plot font: install fonts-dejavu-core (looked for {})", FONT_PATHS.join(", ")))
    })
    .clone()
    .map_err(|m| plot_err(path, m))
}

/// Colours of series, cycled.
pub const SERIES: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// A log axis's range: the decades around the positive finite `values` (1e-12..1 if none).
pub fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in values.filter(|v| *v > 0.0 && v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(lo.is_finite() && hi > 0.0) {
        return (1e-12, 1.0);
    }
    (10f64.powf(lo.log10().floor()), 10f64.powf(hi.log10().ceil().max(lo.log10().floor() + 1.0)))
}

/// A tick's value as a reader writes it: as many decimals as ticks `step` apart need, no
/// trailing zeros, and a short exponent below 0.01 and from 10⁵ on — 0.8, 18, 0.25,
/// 1e-3, 2.5e5 (not 8.000e-1 or 1.800e1).
pub fn tick_label(v: f64, step: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v.is_finite() { "0".into() } else { v.to_string() };
    }
    let step = if step.is_finite() && step > 0.0 { step } else { v.abs() * 0.1 };
    let step_exp = step.log10().floor() as i32;
    let trim = |s: String| -> String {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    let magnitude = v.abs().log10().floor() as i32;
    if (-2..5).contains(&magnitude) {
        let decimals = (-step_exp).clamp(0, 8) as usize;
        return trim(format!("{v:.decimals$}"));
    }
    let digits = (magnitude - step_exp).clamp(0, 6) as usize;
    let text = format!("{v:.digits$e}");
    match text.split_once('e') {
        Some((mantissa, exp)) => format!("{}e{exp}", trim(mantissa.to_string())),
        None => text,
    }
}

/// The legend, in one style for every plot.
pub fn draw_legend<'a, X, Y>(
    chart: &mut ChartContext<'a, BitMapBackend<'a>, Cartesian2d<X, Y>>,
    path: &Path,
) -> Result<(), PlotError>
where
    X: plotters::coord::ranged1d::Ranged,
    Y: plotters::coord::ranged1d::Ranged,
{
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 18))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| plot_err(path, e))
}

/// Writes an RGB buffer as the PNG `path`.
pub fn save(path: &Path, w: u32, h: u32, rgb: &[u8]) -> Result<(), PlotError> {
    let rgba: Vec<u8> = rgb.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
    crate::render::write_png_rgba8(path, w, h, &rgba).map_err(|e| plot_err(path, e))
}

/// One line of a [`line_chart`]: its legend label and its (x, y) points.
pub struct Line {
    /// The legend's label.
    pub label: String,
    /// The points, in x order.
    pub points: Vec<(f64, f64)>,
}

/// A line chart on linear axes from 0: title, axis descriptions (with units), one coloured
/// line per series with a legend; y ticks formatted by `y_format`. Refused: no point at all,
/// a non-finite coordinate.
pub fn line_chart(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    lines: &[Line],
    y_format: &dyn Fn(&f64) -> String,
) -> Result<(), PlotError> {
    font(path)?;
    let all = || lines.iter().flat_map(|l| l.points.iter());
    if all().next().is_none() {
        return Err(plot_err(path, "nothing to plot"));
    }
    if let Some(p) = all().find(|p| !(p.0.is_finite() && p.1.is_finite())) {
        return Err(plot_err(path, format!("a point is not finite: {p:?}")));
    }
    let x_hi = all().map(|p| p.0).fold(0.0f64, f64::max).max(1.0);
    let y_hi = all().map(|p| p.1).fold(0.0f64, f64::max);
    let (w, h) = (1200u32, 600u32);
    // Headroom for the legend (upper right, about 26 px a line of the ~480 px plot area), so
    // that it sits above the data instead of over it.
    let legend = (26.0 * lines.len() as f64 + 24.0) / 480.0;
    let y_hi = if y_hi > 0.0 { y_hi * 1.05 / (1.0 - legend.min(0.6)) } else { 1.0 };
    let mut buf = vec![0u8; 3 * (w * h) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 26))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(90)
            .build_cartesian_2d(0.0..x_hi, 0.0..y_hi)
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 20))
            .y_label_formatter(y_format)
            .draw()
            .map_err(|e| plot_err(path, e))?;
        for (k, line) in lines.iter().enumerate() {
            let colour = SERIES[k % SERIES.len()];
            chart
                .draw_series(LineSeries::new(line.points.iter().copied(), colour.stroke_width(2)))
                .map_err(|e| plot_err(path, e))?
                .label(line.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3)));
        }
        draw_legend(&mut chart, path)?;
        root.present().map_err(|e| plot_err(path, e))?;
    }
    save(path, w, h, &buf)
}

/// What a picture's colours mean: the colour map from `range.0` to `range.1` (on a log
/// scale when `log`), for the quantity `label`; tick values are shown less `shift` (the
/// spacetime ramp is logarithmic in U + 1 and labelled in U).
pub struct ColourBar<'a> {
    /// The colour map the picture was drawn with.
    pub colormap: &'a crate::render::Colormap,
    /// The values at the map's two ends.
    pub range: (f64, f64),
    /// Values mapped by their logarithm (the range must be positive).
    pub log: bool,
    /// The quantity (and its unit), written along the bar.
    pub label: &'a str,
    /// Subtracted from the values for the tick labels (0 for most fields).
    pub shift: f64,
}

/// Width of the colour-bar panel beside a picture, and height of the title above it.
pub const BAR_WIDTH: u32 = 240;
/// Height of the title strip above a picture.
pub const TITLE_HEIGHT: u32 = 50;

/// A rendered picture (RGBA, `size`) with `title` above it and a colour bar beside it (as
/// ParaView's and GLVis's scalar bars show: the map, tick values, the quantity, "log" when
/// logarithmic), placed outside the picture so it hides no data; written as the PNG `path`.
pub fn picture_with_colour_bar(
    rgba: &[u8],
    size: (u32, u32),
    bar: &ColourBar<'_>,
    title: &str,
    path: &Path,
) -> Result<(), PlotError> {
    font(path)?;
    let (pw, ph) = size;
    if rgba.len() != 4 * (pw as usize) * (ph as usize) {
        return Err(plot_err(
            path,
            format!("a {pw}×{ph} picture needs {} bytes, got {}", 4 * pw * ph, rgba.len()),
        ));
    }
    let (w, h) = (pw + BAR_WIDTH, ph.max(300) + TITLE_HEIGHT);
    let mut buf = vec![255u8; 3 * (w as usize) * (h as usize)];
    for y in 0..ph as usize {
        for x in 0..pw as usize {
            let (s, d) = (4 * (y * pw as usize + x), 3 * ((y + TITLE_HEIGHT as usize) * w as usize + x));
            buf[d..d + 3].copy_from_slice(&rgba[s..s + 3]);
        }
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.draw_text(title, &("sans-serif", 22).into_text_style(&root), (16, 14))
            .map_err(|e| plot_err(path, e))?;
        let (_, right) = root.split_horizontally(pw);
        draw_colour_bar(&right, bar, TITLE_HEIGHT + 20, path)?;
        root.present().map_err(|e| plot_err(path, e))?;
    }
    save(path, w, h, &buf)
}

/// The colour bar alone, as the viewers show it beside their picture: [`BAR_WIDTH`] × `height`
/// RGBA pixels, white behind the bar, drawn as [`picture_with_colour_bar`] draws it (`name`
/// stands for the file in errors).
pub fn colour_bar_rgba(bar: &ColourBar<'_>, height: u32, name: &Path) -> Result<Vec<u8>, PlotError> {
    font(name)?;
    let h = height.max(1);
    let mut buf = vec![255u8; 3 * BAR_WIDTH as usize * h as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (BAR_WIDTH, h)).into_drawing_area();
        draw_colour_bar(&root, bar, 20, name)?;
        root.present().map_err(|e| plot_err(name, e))?;
    }
    Ok(buf.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect())
}

/// Draws `bar` in `area` (a panel [`BAR_WIDTH`] wide), `top` pixels below its top edge: the map
/// in 256 steps, ticks labelled with values, the quantity along it. Refused: a range that is
/// not finite, or not positive on a log scale.
fn draw_colour_bar(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    bar: &ColourBar<'_>,
    top: u32,
    path: &Path,
) -> Result<(), PlotError> {
    let (lo, hi) = bar.range;
    if !(lo.is_finite() && hi.is_finite()) || (bar.log && !(lo > 0.0 && hi > lo)) {
        return Err(plot_err(path, format!("colour range [{lo}, {hi}] (log: {})", bar.log)));
    }
    let hi = if hi > lo { hi } else { lo + 1.0 };
    let label = if bar.log { format!("{} (log scale)", bar.label) } else { bar.label.to_string() };
    // The label runs along the bar: a smaller font where it would not fit (a sans-serif
    // character is about 0.55 of the font size wide).
    let along = f64::from(area.dim_in_pixel().1.saturating_sub(top + 30));
    let desc_size = (along / (0.55 * label.chars().count().max(1) as f64)).clamp(10.0, 18.0) as u32;
    let mut builder = ChartBuilder::on(area);
    builder.margin_top(top).margin_left(24).margin_bottom(30).margin_right(20).y_label_area_size(110);
    const STEPS: usize = 256;
    let colour = |t: f64| {
        let c = bar.colormap.sample(t);
        RGBColor((255.0 * c[0]) as u8, (255.0 * c[1]) as u8, (255.0 * c[2]) as u8)
    };
    // The bar's axis is linear in the ramp's coordinate: the value, or its logarithm (so a log
    // range of less than a decade still gets ticks); labels show the value.
    let (a, b) = if bar.log { (lo.log10(), hi.log10()) } else { (lo, hi) };
    let (log, shift) = (bar.log, bar.shift);
    let value = move |y: f64| if log { 10f64.powf(y) } else { y };
    let mut chart = builder.build_cartesian_2d(0.0..1.0, a..b).map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .x_labels(0)
        .y_desc(label.as_str())
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", desc_size))
        // A tick at zero comes out of the axis's arithmetic as ±1e-16: shown as 0.
        .y_label_formatter(&|y: &f64| {
            let v = value(*y) - shift;
            let v = if v.abs() < 1e-12 * (hi - lo).abs().max(hi.abs()) { 0.0 } else { v };
            // Ticks about a tenth of the range apart (on a log scale, of the value itself).
            tick_label(v, if log { 0.1 * v.abs() } else { 0.1 * (hi - lo) })
        })
        .draw()
        .map_err(|e| plot_err(path, e))?;
    chart
        .draw_series((0..STEPS).map(|k| {
            let (s0, s1) = (k as f64 / STEPS as f64, (k + 1) as f64 / STEPS as f64);
            Rectangle::new(
                [(0.0, a + s0 * (b - a)), (1.0, a + s1 * (b - a))],
                colour(0.5 * (s0 + s1)).filled(),
            )
        }))
        .map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// A line segment over a picture: pixel coordinates (x right, y down) of its ends, its colour.
pub type OverlayLine = ((f64, f64), (f64, f64), [u8; 3]);

/// A text label over a picture: pixel position of its top-left corner, the text, its colour.
pub type OverlayLabel = ((f64, f64), String, [u8; 3]);

/// Draws `lines` (2 px wide) and `labels` over the RGBA picture `rgba` of `size`, in place (the
/// outline and axis triad of [`crate::picture::draw_overlay`]); `name` stands for the file in
/// errors. Parts outside the picture are clipped.
pub fn draw_over_picture(
    rgba: &mut [u8],
    size: (u32, u32),
    lines: &[OverlayLine],
    labels: &[OverlayLabel],
    name: &Path,
) -> Result<(), PlotError> {
    let (w, h) = size;
    if rgba.len() != 4 * (w as usize) * (h as usize) {
        return Err(plot_err(
            name,
            format!("a {w}×{h} picture needs {} bytes, got {}", 4 * w * h, rgba.len()),
        ));
    }
    if !labels.is_empty() {
        font(name)?;
    }
    let mut buf: Vec<u8> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        // Far outside the picture a coordinate would overflow i32: clamp first (a clipped end
        // keeps the segment's direction only approximately, and lines that far out are not
        // visible anyway).
        let px = |(x, y): (f64, f64)| (x.clamp(-1e5, 1e5).round() as i32, y.clamp(-1e5, 1e5).round() as i32);
        for &(a, b, [r, g, bl]) in lines {
            let style = RGBColor(r, g, bl).stroke_width(2);
            root.draw(&PathElement::new(vec![px(a), px(b)], style)).map_err(|e| plot_err(name, e))?;
        }
        for (at, text, [r, g, bl]) in labels {
            let style = ("sans-serif", 16).into_font().color(&RGBColor(*r, *g, *bl));
            root.draw_text(text, &style, px(*at)).map_err(|e| plot_err(name, e))?;
        }
        root.present().map_err(|e| plot_err(name, e))?;
    }
    for (d, s) in rgba.chunks_exact_mut(4).zip(buf.chunks_exact(3)) {
        d[..3].copy_from_slice(s);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_read_as_people_write_them() {
        for (v, step, want) in [
            (0.8, 0.1, "0.8"),
            (18.0, 2.0, "18"),
            (0.25, 0.05, "0.25"),
            (1e-3, 1e-4, "1e-3"),
            (1.5e-4, 1e-5, "1.5e-4"),
            (250_000.0, 50_000.0, "2.5e5"),
            (-0.5, 0.1, "-0.5"),
            (0.0, 0.1, "0"),
            (3.0, 0.25, "3"),
            (1234.4, 1.0, "1234"),
        ] {
            assert_eq!(tick_label(v, step), want, "{v} with ticks {step} apart");
        }
    }

    #[test]
    fn a_line_chart_has_its_lines_and_refuses_nothing_or_nan() {
        let dir = tempfile_dir();
        let path = dir.join("chart.png");
        let lines = [
            Line { label: "one".into(), points: vec![(0.0, 0.01), (1.0, 0.02), (2.0, 0.015)] },
            Line { label: "two".into(), points: vec![(0.0, 0.005), (2.0, 0.03)] },
        ];
        line_chart(&path, "title", "frame", "error (%)", &lines, &|v| format!("{:.1} %", 100.0 * v))
            .expect("drawn");
        let (w, h, rgba) = crate::render::read_png_rgba8(&path).expect("a PNG");
        assert_eq!((w, h), (1200, 600));
        // Both series' colours appear (lines drawn), and black (axes and text).
        for c in [SERIES[0], SERIES[1], RGBColor(0, 0, 0)] {
            assert!(rgba.chunks_exact(4).any(|p| p[..3] == [c.0, c.1, c.2]), "{c:?} missing");
        }
        assert!(line_chart(&path, "t", "x", "y", &[], &|v| v.to_string()).is_err());
        let nan = [Line { label: "nan".into(), points: vec![(0.0, f64::NAN)] }];
        assert!(line_chart(&path, "t", "x", "y", &nan, &|v| v.to_string()).is_err());
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn a_picture_gets_a_colour_bar_beside_it_and_keeps_its_pixels() {
        let dir = tempfile_dir();
        let path = dir.join("bar.png");
        let (pw, ph) = (64u32, 400u32);
        let rgba: Vec<u8> = (0..pw * ph).flat_map(|i| [(i % 251) as u8, 7, 9, 255]).collect();
        let map = crate::render::Colormap::by_name("viridis").expect("viridis");
        for log in [false, true] {
            let bar = ColourBar { colormap: &map, range: (0.5, 20.0), log, label: "u", shift: 0.0 };
            picture_with_colour_bar(&rgba, (pw, ph), &bar, "title", &path).expect("drawn");
            let (w, h, out) = crate::render::read_png_rgba8(&path).expect("a PNG");
            assert_eq!((w, h), (pw + BAR_WIDTH, ph + TITLE_HEIGHT));
            // The picture is untouched, below the title.
            for y in [0, ph / 2, ph - 1] {
                for x in [0, pw / 3, pw - 1] {
                    let (s, d) = (4 * (y * pw + x) as usize, 4 * ((y + TITLE_HEIGHT) * w + x) as usize);
                    assert_eq!(out[d..d + 3], rgba[s..s + 3], "pixel ({x}, {y})");
                }
            }
            // The bar shows both ends of the map.
            for t in [0.0, 1.0] {
                let c = map.sample((t + 0.5 / 256.0f64).min(1.0 - 0.5 / 256.0));
                let want = [(255.0 * c[0]) as u8, (255.0 * c[1]) as u8, (255.0 * c[2]) as u8];
                assert!(out.chunks_exact(4).any(|p| p[..3] == want), "log {log}: end {t} of the map missing");
            }
        }
        let bad = ColourBar { colormap: &map, range: (-1.0, 1.0), log: true, label: "u", shift: 0.0 };
        assert!(picture_with_colour_bar(&rgba, (pw, ph), &bad, "t", &path).is_err());
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn the_colour_bar_alone_shows_the_map_on_white() {
        let map = crate::render::Colormap::by_name("cool-warm").expect("cool-warm");
        let bar = ColourBar { colormap: &map, range: (-2.0, 3.0), log: false, label: "u", shift: 0.0 };
        // Tall enough that each of the bar's 256 steps gets a pixel row of its own.
        let rgba = colour_bar_rgba(&bar, 400, Path::new("legend")).expect("drawn");
        assert_eq!(rgba.len(), 4 * BAR_WIDTH as usize * 400);
        assert_eq!(rgba[..4], [255, 255, 255, 255], "white in the corner");
        for t in [0.0, 1.0] {
            let c = map.sample((t + 0.5 / 256.0f64).min(1.0 - 0.5 / 256.0));
            let want = [(255.0 * c[0]) as u8, (255.0 * c[1]) as u8, (255.0 * c[2]) as u8];
            assert!(rgba.chunks_exact(4).any(|p| p[..3] == want), "end {t} of the map missing");
        }
        let bad = ColourBar { colormap: &map, range: (f64::NAN, 1.0), log: false, label: "u", shift: 0.0 };
        assert!(colour_bar_rgba(&bad, 240, Path::new("legend")).is_err());
    }

    /// A scratch directory of this test's own (the tests run in parallel).
    fn tempfile_dir() -> PathBuf {
        tempfile::Builder::new().prefix("galerkin-plot-").tempdir().expect("scratch").keep()
    }
}
