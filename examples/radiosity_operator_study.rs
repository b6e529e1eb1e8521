//! The reduced radiosity operator four ways, on frames of the two animation sequences and the
//! corners of the design space (docs/radiosity.md, "The reduced operator corrected at the
//! training configurations"):
//!
//! - **chain**: Table 2's reduced operator alone, `Î − Ê ⊗₂ p̂`;
//! - **corrected**: the chain plus the blend, by Eq. 17's weights, of its discrepancy from the
//!   exact projected operator at the training configurations (what `radiosity train` stores);
//! - **interpolated**: the exact projected operators of the training configurations blended by
//!   Eq. 17's weights, without the chain;
//! - **exact**: the frame's own exact operator projected on `B_b` (the Galerkin floor),
//!
//! each solved for `b̂` and lifted, against the full radiosity over the receiving surfaces,
//! beside the best fit in `B_b`. The model must be Table 2's chain alone, trained from the
//! same scene with the default samples and seed:
//!
//! ```sh
//! galerkin radiosity train scenes/radiosity/two_rooms_small.toml --no-operator-correction \
//!     --near-field centroid --radiosity-energy 0.999 --out out/radiosity-small-chain
//! cargo run --release --example radiosity_operator_study -- \
//!     scenes/radiosity/two_rooms_small.toml out/radiosity-small-chain [frame stride: 20]
//! ```

use anyhow::{bail, Context, Result};
use faer::linalg::solvers::Solve;
use galerkin::radiosity::compare::{relative_error_over, sequence};
use galerkin::radiosity::full_radiosity_of;
use galerkin::radiosity::operator_correction::{projected_reflection, training_form_factors};
use galerkin::radiosity::reduced::ReducedRadiosity;
use galerkin::radiosity::train::{
    box_corners, sample_parameters, solve_configurations, DesignSpace, TrainOptions,
};
use galerkin::radiosity::SceneSpec;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(scene), Some(dir)) = (args.get(1), args.get(2)) else {
        bail!("usage: radiosity_operator_study SCENE MODEL_DIR [FRAME_STRIDE]");
    };
    let stride: usize = args.get(3).map_or(Ok(20), |s| s.parse()).context("the frame stride")?;
    let spec = SceneSpec::load(std::path::Path::new(scene))?;
    let model = ReducedRadiosity::load(std::path::Path::new(dir))?;
    if model.has_operator_correction() {
        bail!("{dir}: train the model with --no-operator-correction (the study adds the correction itself)");
    }
    let options =
        TrainOptions { near_correction: None, operator_correction: false, ..TrainOptions::default() };
    let params = sample_parameters(&spec.ranges(), &spec.defaults(), options.samples, options.seed);
    eprintln!("solving the {} training configurations…", params.len());
    let configurations = solve_configurations(&spec, &params, &options, &|_| {})?;
    let basis = model.model().basis("b").context("no radiosity basis")?.matrix().clone();
    let m = basis.shape()[1];
    let identity = |k: usize| f64::from(u8::from(k / m == k % m));
    let exact_at = |f: &galerkin::radiosity::FormFactors, albedo: &[[f64; 3]]| -> Vec<f64> {
        let r = projected_reflection(f, albedo, &basis);
        (0..m * m).map(|k| identity(k) - r[k]).collect()
    };
    let chain_at = |mesh: &galerkin::radiosity::SceneMesh| -> Result<Vec<f64>> {
        Ok(model.reduced_operator(mesh)?.data().to_vec())
    };
    let mut training = Vec::new();
    for c in &configurations {
        let mesh = spec.mesh(&c.params)?;
        training.push((exact_at(&training_form_factors(c, options.near), &mesh.albedo), chain_at(&mesh)?));
    }
    let mut tests: Vec<(String, Vec<f64>)> = Vec::new();
    for (which, frames) in [(0usize, 420usize), (1, 500)] {
        for f in (0..frames).step_by(stride.max(1)) {
            tests.push((
                format!("sequence {} frame {f}", which + 1),
                sequence(&spec.ranges(), which, f, frames),
            ));
        }
    }
    for (k, p) in box_corners(&spec.ranges()).into_iter().enumerate() {
        tests.push((format!("corner {k}"), p));
    }
    let names = ["best fit", "exact", "chain", "corrected", "interpolated"];
    println!("configuration,{}", names.join(","));
    let mut sums = [0.0; 5];
    let mut worst = [0.0f64; 5];
    for (name, p) in &tests {
        let full = full_radiosity_of(spec.mesh(p)?, &spec.lights)?;
        let n = full.radiosity.len();
        let chain = chain_at(&full.mesh)?;
        let ghat = model.model().project_input("g", &full.mesh.g())?;
        let (_, x) = model.learned_visibility().predict(&ghat);
        let (mut corrected, mut interpolated) = (chain.clone(), vec![0.0; m * m]);
        for ((exact, reduced), w) in training.iter().zip(&x) {
            for k in 0..m * m {
                corrected[k] += w * (exact[k] - reduced[k]);
                interpolated[k] += w * exact[k];
            }
        }
        let stacked = galerkin::radiosity::chain::stack_channels(&full.emission);
        let project = |v: &[f64]| -> Vec<f64> {
            (0..m).map(|k| (0..3 * n).map(|r| basis.data()[r * m + k] * v[r]).sum()).collect()
        };
        let ehat = project(&stacked);
        let solve = |op: &[f64]| -> Vec<f64> {
            let a = faer::Mat::<f64>::from_fn(m, m, |i, j| op[i * m + j]);
            let y = a.full_piv_lu().solve(faer::Mat::<f64>::from_fn(m, 1, |i, _| ehat[i]));
            (0..m).map(|i| y[(i, 0)]).collect()
        };
        let fit = project(&galerkin::radiosity::chain::stack_channels(&full.radiosity));
        let receiving: Vec<usize> = (0..n).filter(|&i| !full.mesh.kind[i].is_opening()).collect();
        let error = |bhat: &[f64]| -> Result<f64> {
            let b = model.model().lift(bhat)?;
            let b: Vec<[f64; 3]> = (0..n).map(|i| [b[i], b[n + i], b[2 * n + i]]).collect();
            Ok(relative_error_over(&b, &full.radiosity, &full.geometry.areas, &receiving))
        };
        let e = [
            error(&fit)?,
            error(&solve(&exact_at(&full.form_factors, &full.mesh.albedo)))?,
            error(&solve(&chain))?,
            error(&solve(&corrected))?,
            error(&solve(&interpolated))?,
        ];
        println!("{name},{}", e.map(|v| format!("{v:.5}")).join(","));
        for q in 0..5 {
            sums[q] += e[q];
            worst[q] = worst[q].max(e[q]);
        }
    }
    for q in 0..5 {
        eprintln!(
            "{:12}: mean {:.2} %, worst {:.2} % over {} configurations (receiving surfaces)",
            names[q],
            100.0 * sums[q] / tests.len() as f64,
            100.0 * worst[q],
            tests.len()
        );
    }
    Ok(())
}
