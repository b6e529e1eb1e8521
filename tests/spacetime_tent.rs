//! The tent-pitched scenarios of seed 003 §5 (CPU only): requested element counts, validity,
//! order, tiling of slices, causality, materials, streaming, and convergence of the projected
//! analytic fields.

use galerkin::spacetime::cubic::evaluate;
use galerkin::spacetime::mesh::six_volume;
use galerkin::spacetime::scenario::{generate, generate_streaming, materials, GeneratedElement, Scenario};
use galerkin::spacetime::slice::slice;
use galerkin::spacetime::tent::{
    pitch_tents, tent_mesh, Homogeneous, TentOptions, TentProblem, Triangulation,
};
use galerkin::spacetime::SpacetimeMesh;

const REQUEST: usize = 10_000;

fn centroid(c: [[f64; 3]; 4]) -> [f64; 3] {
    std::array::from_fn(|j| 0.25 * (c[0][j] + c[1][j] + c[2][j] + c[3][j]))
}

#[test]
fn scenario_names_round_trip() {
    for s in Scenario::ALL {
        assert_eq!(s.name().parse::<Scenario>(), Ok(s));
        assert_eq!(s.to_string(), s.name());
    }
    assert!("pulses".parse::<Scenario>().unwrap_err().contains("crack, inclusions, booster"));
    assert_eq!(materials(Scenario::Inclusions).len(), 3);
    assert_eq!(materials(Scenario::Crack).len(), 1);
}

/// Each scenario at about 10⁴ elements: the count within 10 % of the request, a valid
/// mesh (finite coefficients, non-degenerate elements) sorted by lowest time, spacetime volume
/// = area × duration, slices tiling the domain at slab boundaries, vertex times and generic
/// times (relative 1e-9: rounding of ~10³ polygon areas is ~1e-14, a missing element ≥ 1e-4),
/// the causality bound on every tent, a non-zero field, several materials for the composite.
#[test]
fn scenarios_hit_the_count_and_tile_spacetime() {
    for s in Scenario::ALL {
        let mesh = generate(s, REQUEST);
        let n = mesh.tets.len();
        let ratio = n as f64 / REQUEST as f64;
        assert!((0.9..=1.1).contains(&ratio), "{s}: {n} elements for {REQUEST}");
        mesh.validate().unwrap();
        let low = mesh.lowest_times();
        assert!(low.windows(2).all(|w| w[0] <= w[1]), "{s}: not sorted");
        let setup = s.setup_for(REQUEST);
        let (area, duration) = (setup.base.area(), setup.model.duration());
        let volume: f64 = (0..n).map(|e| six_volume(mesh.corners(e)) / 6.0).sum();
        assert!((volume / (area * duration) - 1.0).abs() < 1e-9, "{s}: volume {volume}");
        let mut times: Vec<f64> = setup.options.slab_times[1..].to_vec();
        times.extend(mesh.vertices.iter().step_by(101).map(|p| p[2]).filter(|&t| t > 0.0));
        times.extend([0.31, 0.62, 0.93].map(|f| f * duration));
        for t in times {
            let a: f64 = slice(&mesh, t).iter().map(|p| p.area()).sum();
            assert!((a / area - 1.0).abs() < 1e-9, "{s}: slice at {t} has area {a}, domain {area}");
        }
        // The causality bound, checked on the streamed tents of the same set-up.
        let mut checked = 0;
        pitch_tents(&setup.base, &setup.model, &setup.options, &mut |t| {
            let [a, b, vo, vn] = t.corners;
            let tri = [[vo[0], vo[1]], [a[0], a[1]], [b[0], b[1]]];
            let twice_area = (a[0] - vo[0]) * (b[1] - vo[1]) - (b[0] - vo[0]) * (a[1] - vo[1]);
            let h = twice_area / (b[0] - a[0]).hypot(b[1] - a[1]);
            let allowed = a[2].min(b[2]) + setup.options.safety * h / setup.model.wave_speed(&tri);
            assert!(vn[2] > vo[2] && vn[2] <= allowed + 1e-12, "{s}: lift to {} above {allowed}", vn[2]);
            checked += 1;
        })
        .unwrap();
        assert_eq!(checked, n);
        let speed = (0..n)
            .map(|e| {
                let f = &mesh.fields[e];
                evaluate(
                    &f.frame,
                    &mesh.materials[f.material as usize],
                    &f.coefficients,
                    centroid(mesh.corners(e)),
                )
                .speed
            })
            .fold(0.0, f64::max);
        assert!(speed > 1e-3, "{s}: the field is (nearly) at rest everywhere: {speed}");
        let used: std::collections::BTreeSet<u32> = mesh.fields.iter().map(|f| f.material).collect();
        let want = if s == Scenario::Inclusions { 3 } else { 1 };
        assert_eq!(used.len(), want, "{s}: materials used {used:?}");
        assert_eq!(mesh.materials, materials(s));
    }
}

/// Refinement follows the fronts: every slab's triangulation is refined somewhere, slabs differ
/// (so their shared planes are not conforming), and the composite's stiff fibres get shorter
/// tents than the matrix.
#[test]
fn refinement_follows_the_fronts() {
    for s in Scenario::ALL {
        let setup = s.setup(8);
        let stats =
            galerkin::spacetime::tent::count_tents(&setup.base, &setup.model, &setup.options).unwrap();
        let base = setup.base.triangles.len();
        assert!(stats.slab_triangles.iter().all(|&t| t > base), "{s}: {:?} vs {base}", stats.slab_triangles);
        let distinct: std::collections::BTreeSet<usize> = stats.slab_triangles.iter().copied().collect();
        assert!(distinct.len() > 1, "{s}: every slab refined alike");
    }
    // Elements per unit spacetime volume of the matrix and of the stiff core fibre (tents are
    // 2.45 times shorter there), on a finer set-up streamed without projection.
    let setup = Scenario::Inclusions.setup(16);
    let mut per_material = [(0.0, 0.0); 3];
    pitch_tents(&setup.base, &setup.model, &setup.options, &mut |t| {
        let m = &mut per_material[t.material as usize];
        m.0 += 1.0;
        m.1 += six_volume(t.corners) / 6.0;
    })
    .unwrap();
    let density = per_material.map(|(count, volume)| count / volume);
    eprintln!("elements per spacetime volume (matrix, fibres, core): {density:?}");
    assert!(density[2] > 1.5 * density[0], "{density:?}");
}

#[test]
fn streaming_yields_the_mesh_in_order() {
    let mesh = generate(Scenario::Booster, REQUEST);
    let mut records: Vec<GeneratedElement> = Vec::new();
    let summary = generate_streaming(Scenario::Booster, REQUEST, &mut |r| records.push(r.clone()));
    assert_eq!(summary.elements, mesh.tets.len());
    assert_eq!(records.len(), mesh.tets.len());
    assert_eq!(summary.vertices, mesh.vertices.len());
    for (e, r) in records.iter().enumerate() {
        assert_eq!(r.corners, mesh.corners(e));
        assert_eq!(r.material, mesh.fields[e].material);
        assert_eq!(r.frame, mesh.fields[e].frame);
        assert_eq!(r.coefficients, mesh.fields[e].coefficients);
    }
}

/// Largest |projected − analytic| displacement at element centroids, over the amplitude.
fn centroid_error(mesh: &SpacetimeMesh, field: &impl Fn([f64; 3]) -> [f64; 2]) -> f64 {
    (0..mesh.tets.len())
        .map(|e| {
            let f = &mesh.fields[e];
            let x = centroid(mesh.corners(e));
            let got = evaluate(&f.frame, &mesh.materials[0], &f.coefficients, x).displacement;
            let want = field(x);
            (got[0] - want[0]).hypot(got[1] - want[1])
        })
        .fold(0.0, f64::max)
        / galerkin::spacetime::scenario::AMPLITUDE
}

/// The projection of a smooth field converges: on a patch of each scenario, while a front
/// crosses it, halving the mesh size cuts the largest centroid error by more than 4 (the
/// cubic's L2 projection converges like h⁴ in the limit), and on the fine patch (cells of
/// a third of the pulse width) the error is below 0.1 % of the amplitude (measured: 2e-5 and
/// less; the coarse patches, cells of two thirds of the width, are at 3e-4 and less).
#[test]
fn projection_converges_to_the_analytic_field() {
    // (scenario, patch origin, time window) with a front crossing the patch during the window.
    let cases = [
        (Scenario::Crack, [0.44, 0.0], (0.53, 0.56)),
        (Scenario::Inclusions, [0.44, 0.3], (0.37, 0.40)),
        (Scenario::Booster, [0.6, -0.06], (0.1, 0.13)),
    ];
    for (s, origin, (t0, t1)) in cases {
        let model = s.model(64);
        let field = |p: [f64; 3]| model.displacement(p);
        let c = model.materials()[0].p_wave_speed();
        let errors: Vec<f64> = [6, 12]
            .iter()
            .map(|&n| {
                let patch = Triangulation::rectangle(origin, [0.12, 0.12], n, n).unwrap();
                let mesh = tent_mesh(
                    &patch,
                    &Homogeneous { wave_speed: c },
                    &TentOptions::new(t0, t1),
                    vec![model.materials()[0]],
                    &field,
                )
                .unwrap();
                centroid_error(&mesh, &field)
            })
            .collect();
        assert!(errors[1] < 0.25 * errors[0] && errors[1] < 1e-3, "{s}: relative errors {errors:?}");
        let moving = (0..=10).any(|k| {
            let p = [origin[0] + 0.06, origin[1] + 0.06, t0 + 0.1 * k as f64 * (t1 - t0)];
            let q = [p[0], p[1], t0];
            (field(p)[0] - field(q)[0]).hypot(field(p)[1] - field(q)[1])
                > 0.1 * galerkin::spacetime::scenario::AMPLITUDE
        });
        assert!(moving, "{s}: no front crosses the patch in the window");
    }
}

/// Generation speed (release build; run with `--ignored --nocapture`).
#[test]
#[ignore]
fn generation_speed() {
    for (s, n) in
        [(Scenario::Crack, 200_000), (Scenario::Booster, 200_000), (Scenario::Inclusions, 1_000_000)]
    {
        let start = std::time::Instant::now();
        let setup = s.setup_for(n);
        let choose = start.elapsed().as_secs_f64();
        let start = std::time::Instant::now();
        let stats =
            galerkin::spacetime::tent::count_tents(&setup.base, &setup.model, &setup.options).unwrap();
        let count = start.elapsed().as_secs_f64();
        let start = std::time::Instant::now();
        let mut m = 0usize;
        let summary = generate_streaming(s, n, &mut |_| m += 1);
        let stream = start.elapsed().as_secs_f64();
        println!(
            "{s}: requested {n}, got {} (resolution {}, safety {:.3}, {} slabs); choosing the set-up {choose:.2} s; \
             dry run {count:.3} s ({:.2e} elements/s); streaming generation {stream:.1} s ({:.3e} elements/s)",
            stats.elements,
            summary.resolution,
            summary.safety,
            summary.slabs,
            stats.elements as f64 / count,
            m as f64 / stream,
        );
    }
}
