//! Spacetime DG rendering (seed 003) on lavapipe with validation on: the GLSL field and
//! shading includes against their Rust twins, the device slicer against the CPU reference,
//! pixel exactness of U, |v| and the normal, edge overdraw, subdivision, and bad input.

mod common;

use galerkin::gpu::{shaders, vk, Buffer, MemoryKind};
use galerkin::render::{phong, ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spacetime::generate::{pulses, structured_mesh};
use galerkin::spacetime::reference::check_flat_pixels;
use galerkin::spacetime::slice::{slice, SlicePolygon};
use galerkin::spacetime::{
    evaluate, ElementRecord, Material, SpacetimeError, SpacetimeMesh, SpacetimeRenderer, SpacetimeView,
};

fn mesh() -> SpacetimeMesh {
    pulses(6000)
}

fn tri_area(t: &[[f32; 2]; 3]) -> f64 {
    let p = t.map(|v| [f64::from(v[0]), f64::from(v[1])]);
    0.5 * ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])).abs()
}

#[test]
fn glsl_field_and_shading_match_their_rust_twins() {
    let gpu = common::gpu();
    let m = mesh();
    let elements: Vec<ElementRecord> = (0..m.tets.len()).map(|e| ElementRecord::of(&m, e)).collect();
    let materials: Vec<[f32; 4]> =
        m.materials.iter().map(galerkin::spacetime::record::gpu_material).collect();
    let r = common::random_f32(4 * 300, 3);
    let mut points = Vec::new();
    let mut phong_in: Vec<[f32; 4]> = Vec::new();
    for k in 0..300 {
        let e = (k * 19) % m.tets.len();
        // A point inside element e: a random convex combination of its corners.
        let w: Vec<f64> = (0..4).map(|i| f64::from(r[4 * k + i].abs()) + 0.05).collect();
        let s: f64 = w.iter().sum();
        let c = m.corners(e);
        let x: [f64; 3] = std::array::from_fn(|j| (0..4).map(|i| w[i] / s * c[i][j]).sum());
        points.push(([x[0] as f32, x[1] as f32, x[2] as f32, e as f32], e));
        phong_in.extend([
            [0.2, 0.5, 0.9, 0.0],
            [r[4 * k], r[4 * k + 1], 1.0, 0.0],
            [-0.4, -0.4, 0.8, 0.0],
            [0.1, -0.7, 0.7, 0.0],
        ]);
    }
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let eb = Buffer::from_slice(&gpu, "elements", &elements, usage).unwrap();
    let pb =
        Buffer::from_slice(&gpu, "points", &points.iter().map(|p| p.0).collect::<Vec<_>>(), usage).unwrap();
    let qb = Buffer::from_slice(&gpu, "phong in", &phong_in, usage).unwrap();
    let ob = Buffer::<[f32; 4]>::new(&gpu, "out", 6 * 300, usage, MemoryKind::GpuOnly).unwrap();
    let mb = Buffer::from_slice(&gpu, "materials", &materials, usage).unwrap();
    let height_scale = 3.0f32;
    galerkin::push_constants! {
        /// `probe/spacetime.comp`'s `Push { uint n; float height_scale; }`.
        struct ProbePush {
            n: u32,
            height_scale: f32,
        }
    }
    let push = ProbePush { n: 300, height_scale };
    let bindings = [eb.binding(), pb.binding(), qb.binding(), ob.binding(), mb.binding()].map(|b| b.unwrap());
    common::run_probe(&gpu, "spacetime probe", shaders::probe::SPACETIME, &bindings, &push, 5);
    let out = ob.download(&gpu).unwrap();
    let (mut max_u, mut max_v, mut max_e) = (0f64, 0f64, 0f64);
    let fields: Vec<_> = points
        .iter()
        .map(|(p, e)| {
            // The f64 reference at the f32 point the shader saw, with the f32-rounded element.
            let g = ElementRecord::of(&m, *e);
            let mat = m.materials[g.material as usize];
            let mat =
                Material { lambda: f64::from(mat.lambda as f32), mu: f64::from(mat.mu as f32), density: 1.0 };
            evaluate(&g.frame(), &mat, &g.coefficients_f64(), [0, 1, 2].map(|k| f64::from(p[k])))
        })
        .collect();
    for f in &fields {
        max_u = max_u.max(f.strain_energy_density);
        max_v = max_v.max(f.speed);
        max_e = max_e.max(f.strain.iter().fold(0.0f64, |a, b| a.max(b.abs())));
    }
    for (k, f) in fields.iter().enumerate() {
        let o = &out[6 * k..6 * k + 6];
        // f32 evaluation of 20-term cubics in local coordinates (|q| ≤ 0.5) with coefficients of
        // the field's size: relative error ~ 20 terms × a few ε₃₂ ≈ 1e-6 of the field's scale;
        // tolerances are 1e-4 of each field's largest value over the probes.
        let near = |a: f32, b: f64, scale: f64, what: &str| {
            assert!(
                (f64::from(a) - b).abs() <= 1e-4 * scale,
                "probe {k} {what}: glsl {a} vs rust {b} (scale {scale})"
            );
        };
        near(o[0][0], f.strain_energy_density, max_u, "U");
        near(o[0][1], f.speed, max_v, "|v|");
        // The slice restriction (the fragment stage's path) gives the same fields.
        near(o[5][0], f.strain_energy_density, max_u, "U (restricted)");
        near(o[5][1], f.speed, max_v, "|v| (restricted)");
        near(o[1][0], f.velocity[0], max_v, "v_x");
        near(o[1][1], f.velocity[1], max_v, "v_y");
        near(o[1][2], f.strain[0], max_e, "ε_xx");
        near(o[1][3], f.strain[1], max_e, "ε_yy");
        near(o[2][0], f.strain[2], max_e, "ε_xy");
        // The normal is a unit vector; where |v| is tiny its direction is ill-conditioned, so
        // it is compared where |v| is at least 1% of the largest speed.
        if f.speed > 0.01 * max_v {
            let n = f.normal(f64::from(height_scale));
            for j in 0..3 {
                near(o[2][1 + j], n[j], 1e-1, "normal");
            }
        }
        let q = &phong_in[4 * k..4 * k + 4];
        let unit = |v: [f32; 4]| {
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            [f64::from(v[0] / l), f64::from(v[1] / l), f64::from(v[2] / l)]
        };
        let want = phong([0.2, 0.5, 0.9], unit(q[1]), unit(q[2]), unit(q[3]));
        for j in 0..3 {
            near(o[4][j], want[j], 1.0, "phong");
        }
    }
}

#[test]
fn the_device_slice_matches_the_reference_and_tiles_the_domain() {
    let gpu = common::gpu();
    // Vertices rounded to f32, as the device stores them, and f32 times: the reference then
    // classifies every corner (t_i < t) exactly as the device does, also when t is exactly a
    // vertex's time.
    let mut m = mesh();
    for v in &mut m.vertices {
        *v = v.map(|x| f64::from(x as f32));
    }
    let mut r = SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap();
    let (t0, t1) = m.time_range();
    let mut layers: Vec<f64> = m.vertices.iter().map(|v| v[2]).collect();
    layers.sort_by(f64::total_cmp);
    layers.dedup();
    assert_eq!(layers.len(), 11, "the generator's 10 time layers");
    // Generic times, and times exactly at a layer of vertices (cuts through vertices, edges
    // and faces).
    let generic = f64::from((t0 + 0.37 * (t1 - t0)) as f32);
    for t in [generic, layers[3], f64::from(((layers[0] + layers[1]) / 2.0) as f32), layers[7]] {
        let cpu = slice(&m, t);
        let cpu_area: f64 = cpu.iter().map(SlicePolygon::area).sum();
        assert!((cpu_area - 1.0).abs() < 1e-12, "t = {t}: reference slice area {cpu_area}");
        let stats = r.slice(t, None).unwrap();
        let tris = r.slice_triangles().unwrap();
        assert_eq!(stats.triangles, tris.len());
        let gpu_area: f64 = tris.iter().map(|(_, t)| tri_area(t)).sum();
        // f32 corners of O(1) size: each triangle's area within ~4 ε₃₂; the total within 1e-5.
        assert!((gpu_area - 1.0).abs() < 1e-5, "t = {t}: device slice area {gpu_area}");
        // Per element: the same polygon area, and every device triangle inside its element's cut.
        let mut per_element = vec![0.0f64; m.tets.len()];
        for (e, t) in &tris {
            per_element[*e as usize] += tri_area(t);
        }
        for p in &cpu {
            let got = per_element[p.element as usize];
            assert!(
                (got - p.area()).abs() < 1e-6,
                "t = {t}, element {}: area {got} vs {}",
                p.element,
                p.area()
            );
        }
        let cut: std::collections::HashSet<u32> = cpu.iter().map(|p| p.element).collect();
        assert!(
            tris.iter().all(|(e, _)| cut.contains(e)),
            "t = {t}: a device triangle from an uncut element"
        );
        // Edges: 3 or 4 per polygon.
        let lines = r.slice_lines().unwrap();
        assert_eq!(lines.len(), cpu.iter().map(|p| p.corners.len()).sum::<usize>());
    }
}

#[test]
fn subdivision_quadrisects_large_triangles() {
    let gpu = common::gpu();
    let m = mesh();
    let mut r = SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap();
    let t = 0.41 * m.time_range().1;
    let plain = r.slice(t, None).unwrap();
    let tris = r.slice_triangles().unwrap();
    let largest = tris.iter().map(|(_, t)| tri_area(t)).fold(0.0, f64::max);
    let sub = r.slice(t, Some(largest / 5.0)).unwrap();
    let fine = r.slice_triangles().unwrap();
    assert!(sub.triangles > plain.triangles);
    let area: f64 = fine.iter().map(|(_, t)| tri_area(t)).sum();
    assert!((area - 1.0).abs() < 1e-5);
    assert!(fine.iter().all(|(_, t)| tri_area(t) <= largest / 5.0 * (1.0 + 1e-4)));
    assert_eq!(sub.lines, plain.lines, "only polygon edges are overdrawn");
}

#[test]
fn pixels_show_the_element_polynomial_at_their_centres() {
    let gpu = common::gpu();
    let m = mesh();
    let mut r = SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap();
    let t = 0.43 * m.time_range().1;
    // With and without the edge overdraw: the lines must stay behind the polygons.
    for edges in [false, true] {
        let view = SpacetimeView { edges, ..SpacetimeView::from_above(r.data().summary(), t) };
        check_pixels(&gpu, &mut r, &m, &view);
    }
}

fn check_pixels(
    gpu: &galerkin::gpu::Gpu,
    r: &mut SpacetimeRenderer,
    m: &SpacetimeMesh,
    view: &SpacetimeView,
) {
    let (w, h) = (160, 160);
    let target = RenderTarget::new(gpu, "data", w, h, ColorFormat::Rgba32F).unwrap();
    let Pixels::Rgba32F(data) = r.render(&target, view).unwrap() else { panic!("float target") };
    // Tolerance 1e-4 of the largest U and |v| (the reference's docs give the reasoning), 1e-2
    // for the normal where |v| is not tiny.
    let check = check_flat_pixels(m, view, r.default_height_scale(), (w, h), &data, 1, 1e-4);
    assert!(check.passed(), "{} failures; first: {:?}", check.failures, check.first_failure);
    assert!(check.checked > (w * h) as usize / 2, "{} pixels checked", check.checked);
    eprintln!(
        "edges {}: {} pixels: worst U error {:.2e}, |v| {:.2e} of max, normal {:.2e}",
        view.edges, check.checked, check.worst_u, check.worst_speed, check.worst_normal
    );
}

/// Background (NaN) pixels whose ray meets z = 0 well inside the domain: cracks.
fn cracks(gpu: &galerkin::gpu::Gpu, r: &mut SpacetimeRenderer, view: &SpacetimeView) -> usize {
    let (w, h) = (320, 240);
    let target = RenderTarget::new(gpu, "data", w, h, ColorFormat::Rgba32F).unwrap();
    let Pixels::Rgba32F(data) = r.render(&target, view).unwrap() else { panic!("float target") };
    let mut n = 0;
    for py in 0..h {
        for px in 0..w {
            let Some(q) = view.camera.pixel_on_plane_z(px, py, w, h, 0.0) else { continue };
            if q.x > 0.2 && q.x < 0.8 && q.y > 0.2 && q.y < 0.8 && data[4 * (py * w + px) as usize].is_nan() {
                n += 1;
            }
        }
    }
    n
}

#[test]
fn edge_overdraw_fills_the_cracks_of_a_discontinuous_height_field() {
    let gpu = common::gpu();
    // A field made deliberately discontinuous: each element's velocity gets its own offset,
    // up to 3% of the largest speed. With heights up to ~12 px on screen, neighbouring slice
    // polygons then disagree on their shared edge's height by up to ~0.7 px: the aliasing
    // cracks of seed 003 Fig. 4, not walls (a jump of many pixels is a real gap in the data,
    // which edge overdraw does not and should not hide).
    let mut m = mesh();
    let max_speed =
        0.1 / SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap().default_height_scale();
    let r = common::random_f32(2 * m.tets.len(), 11);
    for (e, f) in m.fields.iter_mut().enumerate() {
        let wt = f.frame.extent[2];
        f.coefficients[3][0] += 0.03 * max_speed * f64::from(r[2 * e]) * wt;
        f.coefficients[3][1] += 0.03 * max_speed * f64::from(r[2 * e + 1]) * wt;
    }
    let mut rend = SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap();
    let t = 0.5 * m.time_range().1;
    let base = SpacetimeView::looking_at(rend.data().summary(), t);
    // Heights up to ~5% of the domain: the interior test region stays under the surface.
    let view = SpacetimeView { height_scale: Some(0.5 * rend.default_height_scale()), ..base };
    let without = cracks(&gpu, &mut rend, &SpacetimeView { edges: false, ..view });
    let with = cracks(&gpu, &mut rend, &SpacetimeView { edges: true, ..view });
    eprintln!("background pixels inside the domain: {without} without edge overdraw, {with} with");
    assert!(without > 0, "the test needs cracks to fill");
    assert_eq!(with, 0);
}

#[test]
fn colour_output_and_per_vertex_mode() {
    let gpu = common::gpu();
    let m = mesh();
    let mut r = SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap();
    let t = 0.5 * m.time_range().1;
    let target = RenderTarget::new(&gpu, "colour", 200, 150, ColorFormat::Rgba8).unwrap();
    let view = SpacetimeView::looking_at(r.data().summary(), t);
    let Pixels::Rgba8(pixel) = r.render(&target, &view).unwrap() else { panic!("rgba8") };
    let Pixels::Rgba8(vertex) = r.render(&target, &SpacetimeView { per_vertex: true, ..view }).unwrap()
    else {
        panic!("rgba8")
    };
    let bg = galerkin::render::BACKGROUND.map(|v| (v * 255.0).round() as u8);
    let lit = pixel.chunks_exact(4).filter(|p| p[..3] != bg[..3]).count();
    assert!(lit > 200 * 150 / 4, "{lit} pixels drawn");
    let differ = pixel.chunks_exact(4).zip(vertex.chunks_exact(4)).filter(|(a, b)| a != b).count();
    eprintln!("per-vertex colour differs from per-pixel at {differ} of {lit} drawn pixels");
    assert!(differ > 0);
}

/// The benchmarks' cost floor draws the same pixels as the shaded image, in one colour.
#[test]
fn unshaded_mode_covers_the_shaded_pixels_in_one_colour() {
    let gpu = common::gpu();
    let m = mesh();
    let mut r = SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap();
    let t = 0.5 * m.time_range().1;
    let target = RenderTarget::new(&gpu, "colour", 200, 150, ColorFormat::Rgba8).unwrap();
    let view = SpacetimeView { edges: false, ..SpacetimeView::looking_at(r.data().summary(), t) };
    let Pixels::Rgba8(shaded) = r.render(&target, &view).unwrap() else { panic!("rgba8") };
    let Pixels::Rgba8(floor) = r.render(&target, &SpacetimeView { unshaded: true, ..view }).unwrap() else {
        panic!("rgba8")
    };
    let bg = galerkin::render::BACKGROUND.map(|v| (v * 255.0).round() as u8);
    let covered = |p: &[u8]| p[..3] != bg[..3];
    let mut drawn = 0;
    for (s, f) in shaded.chunks_exact(4).zip(floor.chunks_exact(4)) {
        assert_eq!(covered(s), covered(f), "coverage differs: shaded {s:?}, unshaded {f:?}");
        if covered(f) {
            assert_eq!(f, [255, 255, 255, 255]);
            drawn += 1;
        }
    }
    assert!(drawn > 200 * 150 / 4, "{drawn} pixels drawn");
}

#[test]
fn bad_meshes_are_refused_naming_the_element() {
    let mat = Material { lambda: 1.0, mu: 1.0, density: 1.0 };
    let mut m = structured_mesh(2, 2, 2, [1.0, 1.0], 1.0, mat);
    m.validate().unwrap();
    let mut flat = m.clone();
    flat.tets[5][3] = flat.tets[5][0];
    assert!(matches!(flat.validate(), Err(SpacetimeError::Degenerate { element: 5, .. })));
    let mut nan = m.clone();
    nan.fields[7].coefficients[4][1] = f64::NAN;
    let err = nan.validate().unwrap_err();
    assert!(matches!(err, SpacetimeError::NotFinite { element: 7, .. }), "{err}");
    let mut oob = m.clone();
    oob.tets[2][1] = 9999;
    assert!(oob.validate().unwrap_err().to_string().contains("element 2"));
    m.fields.pop();
    assert!(matches!(m.validate(), Err(SpacetimeError::Length { .. })));
}

#[test]
fn with_height_pixels_show_the_polynomial_where_their_ray_meets_the_surface() {
    // The per-vertex heights (|v| evaluated by the slicing passes) and per-pixel U with the
    // height field on, against a CPU reference: each pixel's ray is intersected with the slice
    // triangles lifted to z = height_scale·|v| (|v| in f64 at the f32 corners), the nearest hit
    // taken, and U evaluated there in f64.
    let gpu = common::gpu();
    let m = mesh();
    let mut r = SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap();
    let t = 0.43 * m.time_range().1;
    let view = SpacetimeView { edges: false, ..SpacetimeView::looking_at(r.data().summary(), t) };
    assert!(view.height);
    let (w, h) = (128, 96);
    let target = RenderTarget::new(&gpu, "data", w, h, ColorFormat::Rgba32F).unwrap();
    let Pixels::Rgba32F(data) = r.render(&target, &view).unwrap() else { panic!("float target") };
    let hs = r.default_height_scale();
    let field = |e: u32, x: f64, y: f64| {
        let f = &m.fields[e as usize];
        evaluate(&f.frame, &m.materials[f.material as usize], &f.coefficients, [x, y, t])
    };
    let lifted: Vec<(u32, [[f64; 3]; 3])> = r
        .slice_triangles()
        .unwrap()
        .iter()
        .map(|(e, c)| {
            (
                *e,
                c.map(|p| {
                    let (x, y) = (f64::from(p[0]), f64::from(p[1]));
                    [x, y, hs * field(*e, x, y).speed]
                }),
            )
        })
        .collect();
    let max_u = lifted
        .iter()
        .flat_map(|(e, c)| c.iter().map(move |p| field(*e, p[0], p[1]).strain_energy_density))
        .fold(0.0f64, f64::max);
    let (mut checked, mut ambiguous, mut worst) = (0, 0, 0f64);
    for py in 0..h {
        for px in 0..w {
            let (Some(a), Some(b)) = (
                view.camera.pixel_on_plane_z(px, py, w, h, 0.0),
                view.camera.pixel_on_plane_z(px, py, w, h, 1.0),
            ) else {
                continue;
            };
            let eye = view.camera.eye;
            let d = [a.x - b.x, a.y - b.y, a.z - b.z];
            // Möller–Trumbore against every lifted triangle: (distance, element, hit, min barycentric).
            let mut hits: Vec<(f64, u32, [f64; 2], f64)> = Vec::new();
            for (e, c) in &lifted {
                let e1 = [0, 1, 2].map(|k| c[1][k] - c[0][k]);
                let e2 = [0, 1, 2].map(|k| c[2][k] - c[0][k]);
                let cross = |u: [f64; 3], v: [f64; 3]| {
                    [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
                };
                let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
                let pv = cross(d, e2);
                let det = dot(e1, pv);
                if det.abs() < 1e-300 {
                    continue;
                }
                let tv = [0, 1, 2].map(|k| eye[k] - c[0][k]);
                let u = dot(tv, pv) / det;
                let qv = cross(tv, e1);
                let v = dot(d, qv) / det;
                let s = dot(e2, qv) / det;
                let bary = u.min(v).min(1.0 - u - v);
                if bary >= -1e-3 && s > 0.0 {
                    hits.push((s, *e, [eye[0] + s * d[0], eye[1] + s * d[1]], bary));
                }
            }
            hits.sort_by(|x, y| x.0.total_cmp(&y.0));
            let got = &data[4 * (py * w + px) as usize..][..4];
            let Some(&(s, e, q, bary)) = hits.first() else {
                assert!(got[0].is_nan(), "pixel ({px}, {py}) drawn where no triangle is hit");
                continue;
            };
            // Ambiguous pixels are skipped: rays within 1e-4 (barycentric) of a triangle's edge,
            // where f32 rasterisation may pick the neighbour or miss (the search accepts hits up
            // to 1e-3 outside a triangle so that near misses count as such), and rays meeting a
            // second surface within 1e-5 of the distance (the f32 heights may swap them).
            if bary < 1e-4 || hits.get(1).is_some_and(|h2| h2.0 - s < 1e-5 * s) {
                ambiguous += 1;
                continue;
            }
            assert!(got[0].is_finite(), "pixel ({px}, {py}) not drawn, element {e} hit");
            let want = field(e, q[0], q[1]).strain_energy_density;
            let err = (f64::from(got[0]) - want).abs() / max_u;
            // f32 heights and positions move the hit by ~1e-6 of the domain; U varies on the
            // pulse width (0.08), so ~1e-5 of its scale; 1e-4 leaves a 10× margin.
            assert!(
                err <= 1e-4,
                "pixel ({px}, {py}), element {e}: U {} vs {want} ({err:.1e} of max)",
                got[0]
            );
            worst = worst.max(err);
            checked += 1;
        }
    }
    assert!(checked > (w * h) as usize / 4, "{checked} pixels checked, {ambiguous} ambiguous");
    assert!(ambiguous * 10 < checked, "{ambiguous} ambiguous of {checked}");
    eprintln!("height on: {checked} pixels, {ambiguous} ambiguous skipped, worst U error {worst:.1e} of max");
}

#[test]
fn the_bar_of_fig3_is_pixel_exact_and_per_vertex_colour_is_not() {
    use galerkin::spacetime::bar::{bar1d, BarRenderer};
    use galerkin::spacetime::cubic::seed_log_coordinate;
    let gpu = common::gpu();
    let mesh = bar1d(800);
    let mut r = BarRenderer::new(&gpu, &mesh, &Colormap::viridis()).unwrap();
    let (w, h) = (240, 120);
    let target = RenderTarget::new(&gpu, "bar", w, h, ColorFormat::Rgba32F).unwrap();
    // U_max: the largest U at the element vertices (the colour ramp's top).
    let u_max = (0..mesh.triangles.len())
        .flat_map(|e| mesh.corners(e).map(|p| mesh.evaluate(e, p[0], p[1]).strain_energy_density))
        .fold(0.0f64, f64::max);
    let Pixels::Rgba32F(pixel) = r.render(&target, u_max, false).unwrap() else { panic!("float target") };
    let Pixels::Rgba32F(vertex) = r.render(&target, u_max, true).unwrap() else { panic!("float target") };
    let inside = |e: usize, q: [f64; 2]| {
        let c = mesh.corners(e);
        let d = |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]);
        let s = [d(c[0], c[1]), d(c[1], c[2]), d(c[2], c[0])];
        // Within 1e-9 (in area units) of the triangle: both neighbours are candidates on an edge.
        s.iter().all(|&v| v >= -1e-9) || s.iter().all(|&v| v <= 1e-9)
    };
    let (mut worst_u, mut worst_s_pixel) = (0f64, 0f64);
    let (mut sum_s_vertex, mut worst_s_vertex, mut far_off, mut n) = (0f64, 0f64, 0usize, 0usize);
    for py in 0..h {
        for px in 0..w {
            let q = r.pixel_point(px, py, w, h);
            let got = &pixel[4 * (py * w + px) as usize..][..4];
            let got_vertex = &vertex[4 * (py * w + px) as usize..][..4];
            assert!(got[0].is_finite(), "pixel ({px}, {py}) not covered");
            // Every triangle containing the centre (two or more on a shared edge): one must match.
            let (err, s_true) = (0..mesh.triangles.len())
                .filter(|&e| inside(e, q))
                .map(|e| {
                    let u = mesh.evaluate(e, q[0], q[1]).strain_energy_density;
                    ((f64::from(got[0]) - u).abs() / u_max, seed_log_coordinate(u, u_max))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .expect("a pixel centre in the mesh's window lies in a triangle");
            // f32 evaluation (~1e-6 of the field's scale) at an f32 position (~1e-7 of the bar);
            // U varies on the pulse width 0.05: 1e-4 of the largest U is a 10× margin.
            assert!(err <= 1e-4, "pixel ({px}, {py}) at {q:?}: U error {err:.1e} of max");
            worst_u = worst_u.max(err);
            worst_s_pixel = worst_s_pixel.max((f64::from(got[3]) - s_true).abs());
            let dv = (f64::from(got_vertex[3]) - s_true).abs();
            sum_s_vertex += dv;
            worst_s_vertex = worst_s_vertex.max(dv);
            far_off += usize::from(dv > 0.05);
            n += 1;
        }
    }
    // The colour coordinate shown per pixel is the true one (f32 log); per vertex it is not.
    assert!(worst_s_pixel < 1e-4, "per-pixel colour coordinate off by {worst_s_pixel}");
    assert!(worst_s_vertex > 0.1, "per-vertex colour is unexpectedly exact ({worst_s_vertex})");
    eprintln!(
        "bar: {n} pixels, worst U error {worst_u:.1e} of max; colour coordinate s: per pixel worst {worst_s_pixel:.1e}, \
         per vertex mean {:.3} worst {worst_s_vertex:.3}, {:.1} % of pixels off by > 0.05",
        sum_s_vertex / n as f64,
        100.0 * far_off as f64 / n as f64
    );
}

#[test]
fn u_max_reduced_on_the_device_is_the_largest_pixel_value() {
    let gpu = common::gpu();
    let m = mesh();
    let mut r = SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap();
    let t = 0.6 * m.time_range().1;
    let view = SpacetimeView { u_max: None, ..SpacetimeView::looking_at(r.data().summary(), t) };
    let (w, h) = (200, 120);
    let colour = RenderTarget::new(&gpu, "colour", w, h, ColorFormat::Rgba8).unwrap();
    let device = r.u_max_for(&colour, &view).unwrap();
    // The same data pass read back and reduced here.
    let data = RenderTarget::new(&gpu, "data", w, h, ColorFormat::Rgba32F).unwrap();
    let Pixels::Rgba32F(v) = r.render(&data, &SpacetimeView { u_max: Some(1.0), ..view }).unwrap() else {
        panic!("float target")
    };
    let host = v.chunks_exact(4).map(|p| p[0]).filter(|u| u.is_finite()).fold(0.0f32, f32::max);
    assert!(host > 0.0);
    assert_eq!(device, f64::from(host), "the device maximum is exact (a maximum does not round)");
}
