//! Lagrange triangles and tetrahedra (VTK types 69 and 71) against VTK itself: for orders 1
//! to 10, our node order gives every point the parametric coordinates VTK 9.7 gives it
//! (`vtkLagrangeTriangle` / `vtkLagrangeTetra::GetParametricCoords`), and our basis and its
//! gradient equal VTK's shape functions and derivatives (`InterpolateFunctions`,
//! `InterpolateDerivs`) at two interior points. The fixture is written by
//! `scripts/vtk-simplex-fixtures.py` with 13 significant digits; tolerances: coordinates
//! 1e-12 (exact fractions j/n), values and derivatives 1e-10 of the largest (13 digits, and
//! derivatives of order 10 reach a few hundred).

use galerkin::spectral::simplex::{basis, node_point, vtk_nodes, SimplexShape, MAX_SIMPLEX_ORDER};

fn fixture() -> serde_json::Value {
    let text = std::fs::read_to_string("tests/data/vtk/lagrange_simplices.json").expect("fixture");
    serde_json::from_str(&text).expect("json")
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().expect("array").iter().map(|x| x.as_f64().expect("number")).collect()
}

#[test]
fn node_order_and_basis_are_vtks_for_orders_1_to_10() {
    let data = fixture();
    let cells = data["cells"].as_array().expect("cells");
    assert_eq!(cells.len(), 2 * MAX_SIMPLEX_ORDER);
    for cell in cells {
        let shape = match cell["shape"].as_str() {
            Some("triangle") => SimplexShape::Triangle,
            Some("tetrahedron") => SimplexShape::Tetrahedron,
            s => panic!("shape {s:?}"),
        };
        let n = cell["order"].as_u64().expect("order") as usize;
        let d = shape.dim();
        let nodes = vtk_nodes(shape, n).unwrap();
        let points = cell["points"].as_array().expect("points");
        assert_eq!(nodes.len(), points.len(), "{shape:?} {n}");
        assert_eq!(nodes.len(), shape.node_count(n));
        for (i, (b, p)) in nodes.iter().zip(points).enumerate() {
            assert_eq!(b.iter().sum::<usize>(), n, "{shape:?} {n} node {i}: {b:?}");
            let ours = node_point(shape, n, b);
            let theirs = floats(p);
            for a in 0..d {
                assert!(
                    (ours[a] - theirs[a]).abs() < 1e-12,
                    "{shape:?} order {n} point {i}: {ours:?} vs VTK {theirs:?}"
                );
            }
        }
        for sample in cell["samples"].as_array().expect("samples") {
            let r = floats(&sample["r"]);
            let r = [r[0], r[1], if d == 3 { r[2] } else { 0.0 }];
            let ours = basis(shape, n, &nodes, &r);
            let weights = floats(&sample["weights"]);
            let scale = weights.iter().fold(1.0f64, |m, w| m.max(w.abs()));
            for (i, ((value, _), w)) in ours.iter().zip(&weights).enumerate() {
                assert!(
                    (value - w).abs() < 1e-10 * scale,
                    "{shape:?} {n} at {r:?}: L_{i} {value} vs VTK {w}"
                );
            }
            let sum: f64 = ours.iter().map(|(v, _)| v).sum();
            assert!((sum - 1.0).abs() < 1e-12, "partition of unity: {sum}");
            if let Some(derivatives) = sample.get("derivatives").and_then(|v| v.as_array()) {
                for (a, column) in derivatives.iter().enumerate() {
                    let theirs = floats(column);
                    let scale = theirs.iter().fold(1.0f64, |m, w| m.max(w.abs()));
                    for (i, ((_, g), t)) in ours.iter().zip(&theirs).enumerate() {
                        assert!(
                            (g[a] - t).abs() < 1e-10 * scale,
                            "{shape:?} {n} ∂/∂r{a} L_{i}: {} vs VTK {t}",
                            g[a]
                        );
                    }
                }
            }
        }
    }
}

/// Every node's basis function is 1 there and 0 at every other node (Silvester's binomials;
/// checked in f64 to 1e-12), and orders outside 1 to 10 are refused naming the order.
#[test]
fn each_basis_function_is_one_at_its_node_and_orders_are_checked() {
    for shape in [SimplexShape::Triangle, SimplexShape::Tetrahedron] {
        for n in 1..=MAX_SIMPLEX_ORDER {
            let nodes = vtk_nodes(shape, n).unwrap();
            for (j, b) in nodes.iter().enumerate() {
                let values = basis(shape, n, &nodes, &node_point(shape, n, b));
                for (i, (v, _)) in values.iter().enumerate() {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((v - want).abs() < 1e-12, "{shape:?} {n}: L_{i} at node {j} = {v}");
                }
            }
        }
        for n in [0, MAX_SIMPLEX_ORDER + 1] {
            let err = vtk_nodes(shape, n).unwrap_err().to_string();
            assert!(err.contains(&format!("order {n}")), "{err}");
        }
    }
}

/// Curved order-3 Lagrange triangles (planar) and tetrahedra written by VTK
/// (`tri_curved.vtu`, `tet_curved.vtu`): read back, our geometry map and field equal VTK's
/// `EvaluateLocation` and interpolated field at every sample (1e-12: the same sums in
/// another order), and the inverse map recovers each sample's reference point from its
/// position (1e-10: Newton to 1e-13 of the element's size, through a Jacobian of order 1).
#[test]
fn curved_simplices_vtk_wrote_evaluate_as_vtk_evaluates_them() {
    use galerkin::spectral::simplex_mesh::SimplexElements;
    for (name, shape) in [("tri_curved", SimplexShape::Triangle), ("tet_curved", SimplexShape::Tetrahedron)] {
        let mesh =
            SimplexElements::read(std::path::Path::new(&format!("tests/data/vtk/{name}.vtu"))).unwrap();
        assert_eq!((mesh.shape, mesh.order, mesh.len()), (shape, 3, 2), "{name}");
        assert_eq!(mesh.fields.len(), 1);
        assert_eq!(mesh.fields[0].name, "u");
        let text = std::fs::read_to_string(format!("tests/data/vtk/{name}.json")).unwrap();
        let data: serde_json::Value = serde_json::from_str(&text).unwrap();
        let samples = data["samples"].as_array().unwrap();
        assert_eq!(samples.len(), 6);
        for s in samples {
            let e = s["element"].as_u64().unwrap() as usize;
            let rv = floats(&s["r"]);
            let r = [rv[0], rv[1], if rv.len() > 2 { rv[2] } else { 0.0 }];
            let want = floats(&s["x"]);
            let (x, _) = mesh.map(e, &r);
            for c in 0..3 {
                assert!(
                    (x[c] - want[c]).abs() < 1e-12,
                    "{name} element {e} at {r:?}: x {x:?} vs VTK {want:?}"
                );
            }
            let u = mesh.value(e, 0, &r);
            let want_u = s["u"].as_f64().unwrap();
            assert!((u - want_u).abs() < 1e-12, "{name} element {e} at {r:?}: u {u} vs VTK {want_u}");
            let back = mesh.inverse(e, &x).expect("Newton converges");
            for a in 0..shape.dim() {
                assert!((back[a] - r[a]).abs() < 1e-10, "{name} element {e}: inverse {back:?} vs {r:?}");
            }
        }
    }
}

/// Files that are not one shape of Lagrange simplices are refused naming the file and what
/// is wrong: a quadrilateral file, a cell of no order (a point count between orders).
#[test]
fn other_cells_are_refused_naming_the_file() {
    use galerkin::spectral::simplex_mesh::SimplexElements;
    let quads = std::path::Path::new("tests/data/vtk/quad_cells.vtu");
    let err = SimplexElements::read(quads).unwrap_err().to_string();
    assert!(err.contains("quad_cells.vtu") && err.contains("VTK_LAGRANGE_TRIANGLE = 69"), "{err}");
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string("tests/data/vtk/tri_curved.vtu").unwrap();
    // Element 0 declared with 9 points (no triangle order has 9).
    let bad = text.replacen(">\n          10 20\n", ">\n          9 20\n", 1);
    assert_ne!(bad, text, "the offsets array moved in the fixture");
    let path = dir.path().join("bad.vtu");
    std::fs::write(&path, bad).unwrap();
    let err = SimplexElements::read(&path).unwrap_err().to_string();
    assert!(err.contains("bad.vtu") && err.contains("9 points"), "{err}");
}
