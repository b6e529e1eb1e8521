//! MFEM files, written here by hand from MFEM's documented numbering — H1 DOFs on vertices,
//! then edges (numbered by first appearance, each running from its lower to its higher vertex
//! id), then faces (numbered by first appearance, in the frame of the first element that has
//! them), then element interiors; L2 DOFs element by element — load into exactly the affine
//! geometry and the degree-p polynomial they sample, on quadrilaterals and hexahedra whose
//! shared edges and faces are seen in different orientations by their two elements.

use std::collections::HashMap;
use std::fmt::Write;

mod common;

use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::basis::gauss_lobatto_nodes;
use galerkin::spectral::{load, mfem, Shape};

/// A fixed polynomial of total degree ≤ p.
fn poly(p: usize, x: [f64; 3]) -> f64 {
    let mut s = 0.3;
    for a in 0..=p {
        for b in 0..=p - a {
            for c in 0..=p - a - b {
                let w = ((a * 7 + b * 3 + c * 5) % 11) as f64 / 10.0 - 0.5;
                s += w * x[0].powi(a as i32) * x[1].powi(b as i32) * x[2].powi(c as i32);
            }
        }
    }
    s
}

/// One affine (slightly sheared) map of the whole row of cells: cell `e` is the image of
/// [e, e + 1] × [0, 1]², so neighbours share their edge or face.
fn affine(e: usize, r: [f64; 3]) -> [f64; 3] {
    let x = e as f64 + r[0];
    [x + 0.2 * r[1], 0.1 * x + 0.9 * r[1] + 0.1 * r[2], 0.15 * r[1] + 0.8 * r[2]]
}

/// Corner (0/1 per axis) of MFEM's local vertex k.
const CORNERS: [[usize; 3]; 8] =
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]];
const QUAD_EDGES: [[usize; 2]; 4] = [[0, 1], [1, 2], [2, 3], [3, 0]];
const HEX_EDGES: [[usize; 2]; 12] =
    [[0, 1], [1, 2], [3, 2], [0, 3], [4, 5], [5, 6], [7, 6], [4, 7], [0, 4], [1, 5], [2, 6], [3, 7]];
const HEX_FACES: [[usize; 4]; 6] =
    [[3, 2, 1, 0], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [4, 5, 6, 7]];

/// Two cells side by side; the second lists its vertices starting from another corner, so the
/// shared edge (quadrilaterals) or face (hexahedra) is walked differently by the two cells.
/// Returns the elements' vertex ids and each global vertex's position.
fn two_cells(hex: bool) -> (Vec<Vec<usize>>, Vec<[f64; 3]>) {
    let corners = if hex { 8 } else { 4 };
    let mut ids: HashMap<[i64; 3], usize> = HashMap::new();
    let mut positions = Vec::new();
    let mut elements = Vec::new();
    for e in 0..2 {
        // The second cell's local vertex k sits at the corner of local vertex rot(k): a
        // rotation by a quarter turn about the cell's x axis (hexahedra) or z axis (quads).
        let rot = |k: usize| -> usize {
            if e == 0 {
                k
            } else if hex {
                [3, 2, 6, 7, 0, 1, 5, 4][k]
            } else {
                [1, 2, 3, 0][k]
            }
        };
        let mut el = Vec::new();
        for k in 0..corners {
            let c = CORNERS[rot(k)].map(|v| v as f64);
            let mut x = affine(e, [c[0], c[1], if hex { c[2] } else { 0.0 }]);
            if !hex {
                x[2] = 0.0; // planar quadrilaterals: the file holds (x, y) only
            }
            let key = x.map(|v| (v * 1e9).round() as i64);
            let next = positions.len();
            let id = *ids.entry(key).or_insert_with(|| next);
            if id == next {
                positions.push(x);
            }
            el.push(id);
        }
        elements.push(el);
    }
    (elements, positions)
}

/// Writes the H1 order-p DOF positions of the mesh in MFEM's global order, walking entities
/// (this is the test's own numbering, independent of the reader's per-element lattice walk).
fn h1_positions(elements: &[Vec<usize>], vertices: &[[f64; 3]], p: usize, hex: bool) -> Vec<[f64; 3]> {
    let cp = gauss_lobatto_nodes(p);
    let lerp =
        |a: [f64; 3], b: [f64; 3], t: f64| -> [f64; 3] { std::array::from_fn(|c| a[c] + t * (b[c] - a[c])) };
    let mut out: Vec<[f64; 3]> = vertices.to_vec();
    // Edges by first appearance, lower → higher vertex id.
    let mut seen = HashMap::new();
    let local_edges: &[[usize; 2]] = if hex { &HEX_EDGES } else { &QUAD_EDGES };
    for el in elements {
        for &[a, b] in local_edges {
            let (lo, hi) = (el[a].min(el[b]), el[a].max(el[b]));
            if seen.insert((lo, hi), ()).is_none() {
                for &t in &cp[1..p] {
                    out.push(lerp(vertices[lo], vertices[hi], t));
                }
            }
        }
    }
    // Faces by first appearance, in the first element's frame: DOF (s, t), s fastest, along
    // fv0 → fv1 and fv0 → fv3 (the cells are affine, so the face is a parallelogram).
    if hex {
        let mut seen = HashMap::new();
        for el in elements {
            for f in HEX_FACES {
                let v = f.map(|k| el[k]);
                let mut key = v;
                key.sort_unstable();
                if seen.insert(key, ()).is_none() {
                    let (o, s, t) = (vertices[v[0]], vertices[v[1]], vertices[v[3]]);
                    for j in 1..p {
                        for i in 1..p {
                            out.push(std::array::from_fn(|c| {
                                o[c] + cp[i] * (s[c] - o[c]) + cp[j] * (t[c] - o[c])
                            }));
                        }
                    }
                }
            }
        }
    }
    // Interiors, element by element, lexicographic: through each cell's own corners (its local
    // trilinear map, which is affine here).
    for el in elements {
        let x = |r: [f64; 3]| -> [f64; 3] {
            let mut acc = [0.0; 3];
            for (k, &v) in el.iter().enumerate() {
                let w: f64 = (0..if hex { 3 } else { 2 })
                    .map(|a| if CORNERS[k][a] == 1 { r[a] } else { 1.0 - r[a] })
                    .product();
                for c in 0..3 {
                    acc[c] += w * vertices[v][c];
                }
            }
            acc
        };
        for k in 1..(if hex { p } else { 2 }) {
            for j in 1..p {
                for i in 1..p {
                    out.push(x([cp[i], cp[j], if hex { cp[k] } else { 0.0 }]));
                }
            }
        }
    }
    out
}

fn mesh_text(
    elements: &[Vec<usize>],
    vertices: &[[f64; 3]],
    hex: bool,
    nodes: Option<(&str, &[[f64; 3]], bool)>,
) -> String {
    let mut s = format!(
        "MFEM mesh v1.0\n\n# written by the test\n\ndimension\n{}\n\nelements\n{}\n",
        if hex { 3 } else { 2 },
        elements.len()
    );
    for el in elements {
        let ids: Vec<String> = el.iter().map(|v| v.to_string()).collect();
        writeln!(s, "1 {} {}", if hex { 5 } else { 3 }, ids.join(" ")).unwrap();
    }
    writeln!(s, "\nboundary\n0\n\nvertices\n{}", vertices.len()).unwrap();
    let sdim = if hex { 3 } else { 2 };
    match nodes {
        None => {
            writeln!(s, "{sdim}").unwrap();
            for v in vertices {
                let c: Vec<String> = v[..sdim].iter().map(|x| format!("{x:.17e}")).collect();
                writeln!(s, "{}", c.join(" ")).unwrap();
            }
        }
        Some((collection, dofs, by_vdim)) => {
            writeln!(s, "\nnodes\nFiniteElementSpace\nFiniteElementCollection: {collection}\nVDim: {sdim}\nOrdering: {}\n", u8::from(by_vdim)).unwrap();
            if by_vdim {
                for d in dofs {
                    let c: Vec<String> = d[..sdim].iter().map(|x| format!("{x:.17e}")).collect();
                    writeln!(s, "{}", c.join(" ")).unwrap();
                }
            } else {
                for c in 0..sdim {
                    for d in dofs {
                        writeln!(s, "{:.17e}", d[c]).unwrap();
                    }
                }
            }
        }
    }
    s
}

fn gf_text(collection: &str, values: &[f64]) -> String {
    let mut s =
        format!("FiniteElementSpace\nFiniteElementCollection: {collection}\nVDim: 1\nOrdering: 0\n\n");
    for v in values {
        writeln!(s, "{v:.17e}").unwrap();
    }
    s
}

/// Checks that `mesh` is the affine geometry and carries `poly(p)` exactly.
fn check_exact(mesh: &galerkin::spectral::SpectralMesh, p: usize, what: &str) {
    let hex = mesh.shape == Shape::Hexahedron;
    for e in 0..mesh.elements() {
        for r in [[0.1, 0.2, 0.3], [0.5, 0.5, 0.5], [0.93, 0.71, 0.05], [0.0, 1.0, 0.4]] {
            let (x, v) = if hex {
                (mesh.map_hex(e, r).0, mesh.value_hex(0, 0, e, r))
            } else {
                (mesh.map(e, r[0], r[1]).0, mesh.value(0, 0, e, r[0], r[1]))
            };
            // The map is affine in x; the value must be poly at the mapped point. Both are
            // interpolation of exact data in f64: errors of a few 1e-15 times the Lebesgue
            // constant.
            assert!((v - poly(p, x)).abs() < 1e-10, "{what} element {e} at {r:?}: {v} vs {}", poly(p, x));
        }
    }
}

#[test]
fn h1_quadrilaterals_and_hexahedra_load_exactly() {
    let scratch = common::Scratch::new();
    for hex in [false, true] {
        for p in [2, 3, 4] {
            let (elements, vertices) = two_cells(hex);
            assert_eq!(vertices.len(), if hex { 12 } else { 6 }, "the two cells share an edge or face");
            let dofs = h1_positions(&elements, &vertices, p, hex);
            let dim = if hex { 3 } else { 2 };
            let collection = format!("H1_{dim}D_P{p}");
            for by_vdim in [false, true] {
                let mesh_path = scratch.file(&format!("h1-{hex}-{p}-{by_vdim}.mesh"));
                std::fs::write(
                    &mesh_path,
                    mesh_text(&elements, &vertices, hex, Some((&collection, &dofs, by_vdim))),
                )
                .unwrap();
                let gf_path = scratch.file(&format!("u-{hex}-{p}.gf"));
                let values: Vec<f64> = dofs.iter().map(|x| poly(p, *x)).collect();
                std::fs::write(&gf_path, gf_text(&collection, &values)).unwrap();
                let mesh = load(&mesh_path, std::slice::from_ref(&gf_path)).unwrap();
                assert_eq!(mesh.elements(), 2);
                assert_eq!(mesh.fields[0].name, format!("u-{hex}-{p}"));
                // The geometry is the affine map of each cell (the second cell rotated).
                check_exact(&mesh, p, &format!("H1 hex {hex} p {p} by_vdim {by_vdim}"));
            }
        }
    }
}

#[test]
fn l2_fields_on_straight_meshes_and_solution_streams_load_exactly() {
    let scratch = common::Scratch::new();
    for hex in [false, true] {
        let p = 3;
        let (elements, vertices) = two_cells(hex);
        let dim = if hex { 3 } else { 2 };
        // L2 on Gauss–Lobatto points (T1), element by element, lexicographic, each element
        // through its own corners.
        let cp = gauss_lobatto_nodes(p);
        let mut values = Vec::new();
        for el in &elements {
            for k in 0..(if hex { p + 1 } else { 1 }) {
                for j in 0..=p {
                    for i in 0..=p {
                        let r = [cp[i], cp[j], if hex { cp[k] } else { 0.0 }];
                        let mut x = [0.0; 3];
                        for (q, &v) in el.iter().enumerate() {
                            let w: f64 = (0..dim)
                                .map(|a| if CORNERS[q][a] == 1 { r[a] } else { 1.0 - r[a] })
                                .product();
                            for c in 0..3 {
                                x[c] += w * vertices[v][c];
                            }
                        }
                        values.push(poly(p, x));
                    }
                }
            }
        }
        let collection = format!("L2_T1_{dim}D_P{p}");
        let text = format!(
            "solution\n{}\n{}",
            mesh_text(&elements, &vertices, hex, None),
            gf_text(&collection, &values)
        );
        let path = scratch.file(&format!("solution-{hex}.sol"));
        std::fs::write(&path, text).unwrap();
        let mesh = load(&path, &[]).unwrap();
        assert_eq!(mesh.fields[0].name, "solution");
        check_exact(&mesh, p, &format!("L2 hex {hex}"));
    }
}

#[test]
fn collection_names_and_malformed_files() {
    let scratch = common::Scratch::new();
    use galerkin::spectral::NodeSet;
    let c = mfem::parse_collection("H1_3D_P2").unwrap();
    assert!(c.continuous && c.dim == 3 && c.order == 2 && c.set == NodeSet::GaussLobatto);
    assert_eq!(mfem::parse_collection("H1Pos_2D_P4").unwrap().set, NodeSet::Bernstein);
    assert_eq!(mfem::parse_collection("H1@U_2D_P4").unwrap().set, NodeSet::Equispaced);
    assert_eq!(mfem::parse_collection("L2_2D_P1").unwrap().set, NodeSet::Gauss);
    let c = mfem::parse_collection("L2_T1_3D_P5").unwrap();
    assert!(!c.continuous && c.order == 5 && c.set == NodeSet::GaussLobatto);
    assert!(mfem::parse_collection("ND_2D_P1").is_none());

    let (elements, vertices) = two_cells(false);
    let good = mesh_text(&elements, &vertices, false, None);
    let gf = scratch.file("bad.gf");
    std::fs::write(&gf, gf_text("H1_2D_P1", &[0.0; 5])).unwrap();
    let mesh_path = scratch.file("good.mesh");
    std::fs::write(&mesh_path, &good).unwrap();
    // 5 values for the 6 vertex DOFs of a P1 space.
    assert_eq!(vertices.len(), 6, "the two cells share an edge");
    let e = load(&mesh_path, std::slice::from_ref(&gf)).unwrap_err().to_string();
    // Named by the GridFunction's file, which holds the wrong count (not the mesh's).
    assert!(e.contains("5 values for 6 DOFs") && e.contains("bad.gf"), "{e}");
    // A triangle in a quadrilateral mesh names line and element.
    let bad = good.replacen("1 3 ", "1 2 ", 1);
    std::fs::write(&mesh_path, bad).unwrap();
    let e = load(&mesh_path, std::slice::from_ref(&gf)).unwrap_err().to_string();
    assert!(e.contains("line 10") && e.contains("element 0: geometry 2"), "{e}");
    // An unknown collection names its line.
    std::fs::write(&gf, gf_text("ND_2D_P1", &[0.0; 6])).unwrap();
    std::fs::write(&mesh_path, &good).unwrap();
    let e = load(&mesh_path, std::slice::from_ref(&gf)).unwrap_err().to_string();
    assert!(e.contains("line 2") && e.contains("ND_2D_P1"), "{e}");
    // A mesh without fields.
    let e = load(&mesh_path, &[]).unwrap_err().to_string();
    assert!(e.contains("--gf"), "{e}");
}

/// The loaded curved-node H1 quadrilaterals render pixel-exactly too (every covered pixel
/// against the f64 pull-back, within its f32 bound; none missing).
#[test]
fn mfem_quadrilaterals_render_per_pixel() {
    let scratch = common::Scratch::new();
    let gpu = common::gpu();
    let p = 3;
    let (elements, vertices) = two_cells(false);
    let dofs = h1_positions(&elements, &vertices, p, false);
    let mesh_path = scratch.file("render.mesh");
    std::fs::write(&mesh_path, mesh_text(&elements, &vertices, false, Some(("H1_2D_P3", &dofs, true))))
        .unwrap();
    let gf_path = scratch.file("render.gf");
    let values: Vec<f64> = dofs.iter().map(|x| poly(p, *x)).collect();
    std::fs::write(&gf_path, gf_text("H1_2D_P3", &values)).unwrap();
    let mesh = Arc::new(load(&mesh_path, &[gf_path]).unwrap());
    let mut r = galerkin::spectral::SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
    let (w, h) = (160, 96);
    let target = RenderTarget::new(&gpu, "mfem", w, h, ColorFormat::Rgba32F).unwrap();
    let view = galerkin::spectral::SpectralView { overdraw: false, ..Default::default() };
    let Pixels::Rgba32F(px) = r.render(&target, &view).unwrap() else { unreachable!() };
    let v2 = galerkin::spectral::View2d::fit(&mesh, w, h);
    let report = galerkin::spectral::reference::check_pixels(&mesh, 0, 0, &v2, (w, h), &px);
    assert!(report.covered > 3000 && report.passed(), "{report:?}");
}
