//! Spectral-element files: VTK Lagrange cells written by hand in the point order VTK documents
//! (corners, edges, faces, body) reproduce a degree-n polynomial exactly, on the CPU and in
//! every rendered pixel; our writer round-trips; malformed files name the file and element.

mod common;

use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::generate::annulus;
use galerkin::spectral::reference::rounding_bound;
use galerkin::spectral::{vtu, NodeSet, Shape, SpectralRenderer, SpectralView, View2d};

/// The reference points of a VTK Lagrange quadrilateral (k = None) or hexahedron of order n in
/// VTK's documented order: corners counter-clockwise (bottom then top layer), edge interiors
/// (bottom: (0,0)→(1,0), (1,0)→(1,1), (0,1)→(1,1), (0,0)→(0,1); top likewise; then the
/// vertical edges at (0,0), (1,0), (0,1), (1,1): the order of files before version 2.2, as
/// these declare), face interiors (ξ = 0, ξ = 1, η = 0, η = 1,
/// ζ = 0, ζ = 1, each with its first free axis fastest), then the body, ξ fastest.
fn vtk_points(n: usize, hex: bool) -> Vec<[usize; 3]> {
    let inner = || 1..n;
    let mut pts = Vec::new();
    let layers: &[usize] = if hex { &[0, n] } else { &[0] };
    for &k in layers {
        pts.extend([[0, 0, k], [n, 0, k], [n, n, k], [0, n, k]]);
    }
    for &k in layers {
        pts.extend(inner().map(|i| [i, 0, k]));
        pts.extend(inner().map(|j| [n, j, k]));
        pts.extend(inner().map(|i| [i, n, k]));
        pts.extend(inner().map(|j| [0, j, k]));
    }
    if !hex {
        for j in inner() {
            pts.extend(inner().map(|i| [i, j, 0]));
        }
        return pts;
    }
    for (i, j) in [(0, 0), (n, 0), (0, n), (n, n)] {
        pts.extend(inner().map(|k| [i, j, k]));
    }
    for i in [0, n] {
        for k in inner() {
            pts.extend(inner().map(|j| [i, j, k]));
        }
    }
    for j in [0, n] {
        for k in inner() {
            pts.extend(inner().map(|i| [i, j, k]));
        }
    }
    for k in [0, n] {
        for j in inner() {
            pts.extend(inner().map(|i| [i, j, k]));
        }
    }
    for k in inner() {
        for j in inner() {
            pts.extend(inner().map(|i| [i, j, k]));
        }
    }
    pts
}

/// A total-degree-n polynomial with fixed pseudo-random coefficients.
fn poly(n: usize, x: [f64; 3]) -> f64 {
    let c = common::random_f32(300, n as u64);
    let mut s = 0.0;
    let mut t = 0;
    for a in 0..=n {
        for b in 0..=n - a {
            for d in 0..=n - a - b {
                s += f64::from(c[t]) * x[0].powi(a as i32) * x[1].powi(b as i32) * x[2].powi(d as i32);
                t += 1;
            }
        }
    }
    s
}

/// Affine cells: the parallelogram (or parallelepiped) `cell` of a row of them.
fn affine(cell: usize, r: [f64; 3]) -> [f64; 3] {
    [0.3 + cell as f64 + r[0] + 0.3 * r[1], 0.2 + 0.8 * r[1] + 0.1 * r[2], 0.1 * r[0] + 0.7 * r[2]]
}

/// An ASCII .vtu of `cells` affine Lagrange cells of order n with point data `p` = [`poly`].
fn ascii_vtu(n: usize, hex: bool, cells: usize) -> String {
    let order = vtk_points(n, hex);
    let mut points = String::new();
    let mut data = String::new();
    for c in 0..cells {
        for ijk in &order {
            let mut r = ijk.map(|v| v as f64 / n as f64);
            if !hex {
                r[2] = 0.0;
            }
            let mut x = affine(c, r);
            if !hex {
                x[2] = 0.0;
            }
            points.push_str(&format!("{:.17e} {:.17e} {:.17e}\n", x[0], x[1], x[2]));
            data.push_str(&format!("{:.17e}\n", poly(n, x)));
        }
    }
    let per = order.len();
    let conn: Vec<String> = (0..cells * per).map(|k| k.to_string()).collect();
    let offsets: Vec<String> = (1..=cells).map(|c| (c * per).to_string()).collect();
    let ty = if hex { 72 } else { 70 };
    format!(
        r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="{np}" NumberOfCells="{cells}">
      <PointData Scalars="p">
        <DataArray type="Float64" Name="p" format="ascii">
{data}        </DataArray>
      </PointData>
      <Points>
        <DataArray type="Float64" NumberOfComponents="3" format="ascii">
{points}        </DataArray>
      </Points>
      <Cells>
        <DataArray type="Int64" Name="connectivity" format="ascii">{conn}</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">{offsets}</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">{types}</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
"#,
        np = cells * per,
        conn = conn.join(" "),
        offsets = offsets.join(" "),
        types = vec![ty.to_string(); cells].join(" "),
    )
}

#[test]
fn vtk_lagrange_cells_reproduce_a_degree_n_polynomial() {
    let scratch = common::Scratch::new();
    for hex in [false, true] {
        for n in [1, 2, 3, 5, 8] {
            let path = scratch.file(&format!("poly-{n}-{hex}.vtu"));
            std::fs::write(&path, ascii_vtu(n, hex, 3)).unwrap();
            let mesh = vtu::read(&path).unwrap();
            assert_eq!(mesh.shape, if hex { Shape::Hexahedron } else { Shape::Quadrilateral });
            assert_eq!((mesh.basis.order, mesh.basis.set, mesh.elements()), (n, NodeSet::Equispaced, 3));
            let r = common::random_f32(300, 5);
            for k in 0..100 {
                let e = k % 3;
                let q = [0, 1, 2].map(|a| 0.5 + 0.5 * f64::from(r[3 * k + a]));
                let (value, x) = if hex {
                    (mesh.value_hex(0, 0, e, q), mesh.map_hex(e, q).0)
                } else {
                    (mesh.value(0, 0, e, q[0], q[1]), mesh.map(e, q[0], q[1]).0)
                };
                let mut expect_x = affine(e, [q[0], q[1], if hex { q[2] } else { 0.0 }]);
                if !hex {
                    expect_x[2] = 0.0;
                }
                for c in 0..3 {
                    assert!((x[c] - expect_x[c]).abs() < 1e-12, "order {n} hex {hex}: geometry");
                }
                // Interpolation of a degree-n polynomial at n + 1 nodes per axis is exact; f64
                // rounding of ≤ 729 terms of size ≤ the Lebesgue constant (~30 at n = 8).
                assert!((value - poly(n, x)).abs() < 1e-9, "order {n} hex {hex}: {value} vs {}", poly(n, x));
            }
        }
    }
}

/// The rendered quadrilaterals show p(pixel centre) itself, within each pixel's f32 bound.
#[test]
fn rendered_vtk_quadrilaterals_show_the_polynomial() {
    let scratch = common::Scratch::new();
    let gpu = common::gpu();
    for n in [2, 5, 8] {
        let path = scratch.file(&format!("render-{n}.vtu"));
        std::fs::write(&path, ascii_vtu(n, false, 3)).unwrap();
        let mesh = Arc::new(vtu::read(&path).unwrap());
        let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
        let (w, h) = (192, 96);
        let target = RenderTarget::new(&gpu, "vtu", w, h, ColorFormat::Rgba32F).unwrap();
        let Pixels::Rgba32F(px) = r.render(&target, &SpectralView::default()).unwrap() else {
            unreachable!()
        };
        let view = View2d::fit(&mesh, w, h);
        let mut covered = 0;
        for y in 0..h {
            for x in 0..w {
                let t = &px[4 * (y * w + x) as usize..][..4];
                // Edge overdraw pixels (a rim outside the boundary) show the edge's value.
                if t[3].is_nan() || t[3] < 0.0 {
                    continue;
                }
                covered += 1;
                let p = view.pixel_centre(x, y, w, h);
                let e = t[3] as usize;
                let q = mesh.inverse_map(e, p, [0.5, 0.5]).unwrap().map(|c| c.clamp(0.0, 1.0));
                let bound = rounding_bound(&mesh, 0, 0, e, q);
                let exact = poly(n, [p[0], p[1], 0.0]);
                assert!(
                    (f64::from(t[0]) - exact).abs() <= bound + 1e-9,
                    "order {n} pixel ({x}, {y}): {} vs {exact}",
                    t[0]
                );
            }
        }
        assert!(covered > 5000, "{covered}");
    }
}

#[test]
fn written_vtu_round_trips() {
    let scratch = common::Scratch::new();
    for set in [NodeSet::GaussLobatto, NodeSet::Bernstein] {
        let mesh = annulus(2, 3, 4, 5, set).unwrap();
        let path = scratch.file(&format!("annulus-{}.vtu", set.name()));
        vtu::write(&path, &mesh).unwrap();
        let back = vtu::read(&path).unwrap();
        assert_eq!(back.elements(), mesh.elements());
        let names: Vec<&str> = back.fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["cells", "waves"]);
        let waves = back.field_index(Some("waves")).unwrap();
        assert_eq!(back.fields[waves].steps.len(), mesh.fields[0].steps.len());
        for e in 0..mesh.elements() {
            for (xi, eta) in [(0.1, 0.2), (0.5, 0.5), (0.93, 0.71)] {
                let (a, b) = (mesh.map(e, xi, eta).0, back.map(e, xi, eta).0);
                assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
                for step in 0..mesh.fields[0].steps.len() {
                    let (u, v) = (mesh.value(0, step, e, xi, eta), back.value(waves, step, e, xi, eta));
                    assert!((u - v).abs() < 1e-11, "{set:?} e {e} step {step}: {u} vs {v}");
                }
            }
        }
        assert!(!path.with_extension("vtu.partial").exists());
    }
}

#[test]
fn malformed_vtu_names_file_and_element() {
    let scratch = common::Scratch::new();
    let good = ascii_vtu(2, false, 3);
    let cases = [
        (good.replace(">70 70 70<", ">70 5 70<"), "element 1: cell type 5"),
        (good.replace(">9 18 27<", ">9 18 26<"), "element 2: offset 26"),
        (
            good.replacen(
                "<DataArray type=\"Float64\" Name=\"p\" format=\"ascii\">\n",
                "<DataArray type=\"Float64\" Name=\"p\" format=\"ascii\">\nnan\n",
                1,
            ),
            "array p: 28 values for 27 points",
        ),
        (good.replace(">70 70 70<", ">68 68 68<"), "element 0: cell type 68"),
        (good.replace(">70 70 70<", ">71 71 71<"), "element 0: 9 points is no Tetrahedron"),
        (good[..good.len() / 2].to_string(), "XML"),
    ];
    for (k, (text, expect)) in cases.iter().enumerate() {
        let path = scratch.file(&format!("bad-{k}.vtu"));
        std::fs::write(&path, text).unwrap();
        let e = vtu::read(&path).unwrap_err().to_string();
        assert!(e.contains(expect) && e.contains(&format!("bad-{k}.vtu")), "case {k}: {e}");
    }
    // A NaN value names the element and node.
    let nan = good.replacen(
        "<DataArray type=\"Float64\" Name=\"p\" format=\"ascii\">\n",
        "<DataArray type=\"Float64\" Name=\"p\" format=\"ascii\">\nnan\n",
        1,
    );
    let nan = nan.replacen(&format!("{:.17e}\n", poly(2, affine(0, [0.0; 3]))), "", 1);
    let path = scratch.file("nan.vtu");
    std::fs::write(&path, nan).unwrap();
    let e = vtu::read(&path).unwrap_err().to_string();
    assert!(e.contains("element 0") && e.contains("not finite"), "{e}");
}
