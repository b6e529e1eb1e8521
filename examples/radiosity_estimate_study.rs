//! Forms of the reduced radiosity's cross-validated error estimate (docs/radiosity.md, "How far
//! a reduced answer is from the truth"), against the true errors `radiosity compare --random`
//! measured: for each row of a random.csv (or compare.csv, corners.csv), the model's Eq. 17 weights and its samples'
//! left-out errors, floors and spacing combined several ways, and each form's effectivity
//! (estimate ÷ true error over the receiving surfaces) — min, median, max and how many fall
//! outside [0.5, 10].
//!
//! ```sh
//! galerkin radiosity train scenes/radiosity/two_rooms_small.toml --out out/radiosity-small
//! galerkin radiosity compare scenes/radiosity/two_rooms_small.toml --model out/radiosity-small \
//!     --random 1000 --out out/radiosity-small-compare
//! cargo run --release --example radiosity_estimate_study -- scenes/radiosity/two_rooms_small.toml \
//!     out/radiosity-small out/radiosity-small-compare/random.csv
//! ```

use std::path::Path;

use anyhow::{bail, Context, Result};
use galerkin::radiosity::any_scene::AnyScene;
use galerkin::radiosity::reduced::ReducedRadiosity;
use galerkin::reduce::effectivity::Effectivity;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, model, random] = args.as_slice() else {
        bail!("usage: radiosity_estimate_study SCENE MODEL_DIR random.csv");
    };
    let scene = AnyScene::load(Path::new(scene), None)?;
    let model = ReducedRadiosity::load(Path::new(model))?;
    let v = model.cross_validation().context("the model has no error estimate")?.clone();
    let geometry = model.learned_visibility().geometry().clone();
    let (m, t) = (geometry.shape()[0], geometry.shape()[1]);
    let text = std::fs::read_to_string(random).with_context(|| random.clone())?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().context("an empty table")?.split(',').collect();
    let column =
        |name: &str| header.iter().position(|h| *h == name).with_context(|| format!("no column {name}"));
    let truth_column = column("error_receiving")?;
    // The parameters' columns, wherever they are (compare.csv starts with sequence and frame).
    let params: Vec<usize> = scene.names().iter().map(|n| column(n)).collect::<Result<_>>()?;
    type Form<'a> = (&'a str, &'a dyn Fn(f64, f64, f64) -> f64);
    let forms: [Form; 5] = [
        ("floor + left-out × min(1, d/h)", &|f, e, r| f + e * r.min(1.0)),
        ("floor + left-out × d/h", &|f, e, r| f + e * r),
        ("floor + left-out × min(2, d/h)", &|f, e, r| f + e * r.min(2.0)),
        ("floor + left-out × √(d/h), at most 2 (built)", &|f, e, r| f + e * r.sqrt().min(2.0)),
        ("floor + left-out", &|f, e, _| f + e),
    ];
    let mut pairs: Vec<Vec<(f64, f64)>> = vec![Vec::new(); forms.len() + 2];
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        let p: Vec<f64> = params.iter().map(|&k| cells[k].parse()).collect::<Result<_, _>>()?;
        let truth: f64 = cells[truth_column].parse()?;
        let mesh = scene.space().mesh(&p)?;
        let ghat = model.model().project_input("g", &mesh.g())?;
        let (_, x) = model.learned_visibility().predict(&ghat);
        for (k, (_, form)) in forms.iter().enumerate() {
            let mut eta = 0.0;
            for (s, &weight) in x.iter().enumerate().take(t) {
                if weight == 0.0 {
                    continue;
                }
                let dist = (0..m).map(|i| (ghat[i] - geometry.data()[i * t + s]).powi(2)).sum::<f64>().sqrt();
                eta += weight * form(v.floor[s], v.left_out[s], dist / v.spacing[s]);
            }
            pairs[k].push((eta, truth));
        }
        // The largest over the samples Eq. 17 weights, of the built form and of √(d/h) ≤ 2.
        let mut worst = [0.0f64; 2];
        for (s, &weight) in x.iter().enumerate().take(t) {
            if weight == 0.0 {
                continue;
            }
            let dist = (0..m).map(|i| (ghat[i] - geometry.data()[i * t + s]).powi(2)).sum::<f64>().sqrt();
            let r = dist / v.spacing[s];
            worst[0] = worst[0].max(v.floor[s] + v.left_out[s] * r.min(1.0));
            worst[1] = worst[1].max(v.floor[s] + v.left_out[s] * r.sqrt().min(2.0));
        }
        pairs[forms.len()].push((worst[0], truth));
        pairs[forms.len() + 1].push((worst[1], truth));
    }
    let names: Vec<&str> = forms
        .iter()
        .map(|f| f.0)
        .chain([
            "largest over the weighted samples, min(1, d/h)",
            "largest over the weighted samples, √(d/h) ≤ 2",
        ])
        .collect();
    for (name, p) in names.iter().zip(&pairs) {
        match Effectivity::of(p.iter().copied()) {
            Some(e) => println!("{name}: {e}"),
            None => println!("{name}: no finite effectivity"),
        }
    }
    Ok(())
}
