//! Reduced models on disk (safetensors): a round trip evaluates identically; truncated files,
//! newer versions and shapes that disagree with the metadata are refused with the file named.

mod common;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use galerkin::reduce::{Bases, Basis, Expr, Model, ReducedModel};
use galerkin::tensor::{SparseTensor, Tensor};

fn model_and_bases() -> (Model, Bases) {
    let n = 8;
    let mut q = SparseTensor::new(&[n, n, n]);
    for (e, v) in common::random_f32(200, 4).into_iter().enumerate() {
        q.push(&[e % n, (e / n) % n, (e * 7) % n], f64::from(v));
    }
    let mut k = Tensor::identity(n).scale(3.0);
    k.set(&[0, 1], 0.5);
    k.set(&[1, 0], 0.5);
    let x = Expr::input("x");
    let model =
        Model::new(Expr::tensor("K").inverse().times(1, Expr::tensor("Q").times(1, x.clone()).times(2, x)))
            .with_tensor("Q", &["y", "x", "x"], q)
            .with_tensor("K", &["y", "y"], k)
            .with_input("x", "x");
    let basis = |m: usize, seed: u64| {
        let g =
            Tensor::from_vec(&[n, m], common::random_f32(n * m, seed).into_iter().map(f64::from).collect())
                .unwrap();
        Basis::orthonormalize("b", &g).unwrap()
    };
    let mut bases = Bases::new();
    bases.insert("x".into(), basis(3, 1));
    bases.insert("y".into(), basis(4, 2));
    (model, bases)
}

/// A scratch directory (removed when dropped) and the model path in it.
fn temp(name: &str) -> (tempfile::TempDir, PathBuf) {
    let scratch =
        tempfile::Builder::new().prefix(&format!("galerkin-{name}-")).tempdir().expect("a scratch directory");
    let path = scratch.path().join("model.safetensors");
    (scratch, path)
}

#[test]
fn a_saved_model_loads_and_evaluates_identically() {
    let (model, bases) = model_and_bases();
    let reduced = model.reduce(&bases).unwrap();
    let (_scratch, path) = temp("roundtrip");
    reduced.save(&path).unwrap();
    let loaded = ReducedModel::load(&path).unwrap();
    assert_eq!(loaded, reduced);
    let xhat = [0.3, -1.2, 0.8];
    let inputs: BTreeMap<&str, &[f64]> = [("x", &xhat[..])].into_iter().collect();
    assert_eq!(loaded.evaluate(&inputs).unwrap(), reduced.evaluate(&inputs).unwrap());
    let names: Vec<_> =
        std::fs::read_dir(path.parent().unwrap()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 1, "no temporary file left: {names:?}");
}

/// Rewrites `path` with its tensors and metadata passed through `edit`.
fn rewrite(
    path: &Path,
    edit: impl FnOnce(&mut Vec<(String, Vec<usize>, Vec<u8>)>, &mut HashMap<String, String>),
) {
    let buffer = std::fs::read(path).unwrap();
    let (_, header) = safetensors::SafeTensors::read_metadata(&buffer).unwrap();
    let file = safetensors::SafeTensors::deserialize(&buffer).unwrap();
    let mut meta = header.metadata().clone().unwrap();
    let mut tensors: Vec<(String, Vec<usize>, Vec<u8>)> =
        file.tensors().into_iter().map(|(n, v)| (n, v.shape().to_vec(), v.data().to_vec())).collect();
    edit(&mut tensors, &mut meta);
    let views: Vec<(String, safetensors::tensor::TensorView<'_>)> = tensors
        .iter()
        .map(|(n, s, d)| {
            (n.clone(), safetensors::tensor::TensorView::new(safetensors::Dtype::F64, s.clone(), d).unwrap())
        })
        .collect();
    std::fs::write(path, safetensors::serialize(views, Some(meta)).unwrap()).unwrap();
}

#[test]
fn bad_files_are_refused_with_the_reason() {
    let (model, bases) = model_and_bases();
    let reduced = model.reduce(&bases).unwrap();
    let (_scratch, path) = temp("bad");
    let err = |p: &Path| ReducedModel::load(p).unwrap_err().to_string();

    reduced.save(&path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() - 100]).unwrap();
    let e = err(&path);
    assert!(e.contains("model.safetensors") && e.contains("not a readable safetensors file"), "{e}");

    reduced.save(&path).unwrap();
    rewrite(&path, |_, meta| {
        meta.insert("version".into(), "2".into());
    });
    let e = err(&path);
    assert!(e.contains("newer galerkin") && e.contains("version 2"), "{e}");

    reduced.save(&path).unwrap();
    rewrite(&path, |tensors, _| {
        // tensor/Q is 4 × 3 × 3 (y, x, x); relabel it 4 × 9 × 1 keeping the bytes.
        let q = tensors.iter_mut().find(|t| t.0 == "tensor/Q").unwrap();
        q.1 = vec![4, 9, 1];
    });
    let e = err(&path);
    assert!(e.contains("tensor `Q` axis 1 (basis `x`) has length 9"), "{e}");

    reduced.save(&path).unwrap();
    rewrite(&path, |_, meta| {
        meta.insert("format".into(), "something-else".into());
    });
    assert!(err(&path).contains("not a galerkin reduced model"));
}
