//! The reduced fluid's bases (seed 000 §6.1, §6.3–6.4), each from the training set's
//! snapshots by the core's streaming PCA:
//!
//! - `B_f` from the fluxes: divergence-free by construction (§6.3: every snapshot is), checked
//!   after truncation and orthonormalisation;
//! - `B_u = B_p` from the velocities and the momenta, each reduced, then **interleaved**
//!   (u₁, p₁, u₂, p₂, …), re-orthonormalised and cut at `m_u` columns, so both quantities'
//!   leading modes are kept whatever the cap (§6.1: "we concatenate these bases and
//!   re-orthonormalize"). The inner product is the **Euclidean** one: the same basis must be
//!   orthonormal on both axes of `V̂ = B_pᵀ V B_u` for §4's inverse rule and §A.2's energy
//!   argument, and `V(g)`'s own inner product changes with the geometry;
//! - `B_g` from the geometry sequence, **centred**: the mean geometry is its first column, so
//!   `g ≈ B_g ĝ` carries the mean exactly. The cells a training frame's projected geometry
//!   folds are counted and reported (the bird's wings fold some at any m_g up to 40); the
//!   model is refused only if the reduced volume matrix `V̂(ĝ)` of a training frame is not
//!   positive definite (checked once the tensors are premultiplied), naming the run and frame;
//! - `B_h` from the induced fluxes (absent when no training run moves its mesh);
//! - `B_d` by constraint reduction (§6.4, Wicke, Stanton & Treuille 2009): an orthonormal basis
//!   of the range of the boundary rows of `[D B_f, D B_h]`, so that `B_dᵀ D(B_f f̂ − B_h ĥ) = 0`
//!   holds **iff** `D(B_f f̂ − B_h ĥ) = 0` (the residual lies in that range). Directions with
//!   singular value below [`CONSTRAINT_RANK_TOLERANCE`] are rounding and dropped; the rank is
//!   logged. Absent when the rank is zero (no boundary flux in any snapshot: the tunnel).

use crate::fluid::operators::divergence;
use crate::fluid::FluidError;
use crate::mesh::{SimplexMesh, Topology};
use std::collections::HashMap;
use std::path::Path;

use crate::reduce::{
    load_arrays, pca_across, save_arrays, Basis, Communicator, Pca, SnapshotSource, Truncation,
};
use crate::tensor::Tensor;

use super::training::TrainingSet;

/// Singular values of `D [B_f, B_h]` at or below this count as zero (its columns have unit
/// norm, so this is an absolute scale: the snapshots' boundary fluxes are exact to ~1e-12).
pub const CONSTRAINT_RANK_TOLERANCE: f64 = 1e-9;

/// Largest relative divergence `‖div B_f‖_F / ‖B_f‖_F` a flux basis may keep.
pub const DIVERGENCE_TOLERANCE: f64 = 1e-10;

/// How many modes each basis may keep: the fewest whose σ² reach `energy` of the total, at
/// most the cap (`None`: the number of snapshots).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BasisSizes {
    /// Captured-energy threshold, 0 < energy ≤ 1.
    pub energy: f64,
    /// Cap of `B_f`.
    pub m_f: Option<usize>,
    /// Cap of the merged `B_u = B_p`.
    pub m_u: Option<usize>,
    /// Cap of `B_g` (the mean included).
    pub m_g: Option<usize>,
    /// Cap of `B_h`.
    pub m_h: Option<usize>,
    /// `B_u = B_p` also spans the **mid-step** velocities: each training frame's velocity
    /// advected and diffused over the frame, before its projection ([`advected_velocities`]),
    /// a third basis interleaved with the velocities' and momenta's. The reduced step holds
    /// its advected state in `B_u`; without these the basis has only projected states.
    /// `Default` leaves it off (the paper's §6 bases, what the library's tests pin down); the
    /// command line turns it on unless `--no-mid-step` is given.
    pub mid_step: bool,
}

impl Default for BasisSizes {
    fn default() -> Self {
        Self { energy: 0.9999, m_f: None, m_u: None, m_g: None, m_h: None, mid_step: false }
    }
}

/// One basis's size and the energy fraction it captures.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BasisReport {
    /// Basis name (`f`, `u`, `g`, `h`, `d`).
    pub name: String,
    /// Full dimension.
    pub full: usize,
    /// Columns kept.
    pub columns: usize,
    /// Fraction of Σσ² captured (for `u` the smaller of the velocity's and momentum's; for
    /// `d` 1).
    pub energy: f64,
    /// What else is worth knowing (divergence, constraint rank, geometry error).
    pub note: String,
}

/// The bases of a reduced fluid model.
#[derive(Clone, Debug)]
pub struct FluidBases {
    /// Flux basis `B_f` (faces × m_f).
    pub f: Basis,
    /// Velocity and momentum basis `B_u = B_p` (d·cells × m_u).
    pub u: Basis,
    /// Geometry basis `B_g` (d·vertices × m_g), the mean first.
    pub g: Basis,
    /// Induced-flux basis `B_h` (faces × m_h), if any run moves its mesh.
    pub h: Option<Basis>,
    /// Boundary-flux basis `B_d` (boundary faces × rank), if any snapshot has boundary flux.
    pub d: Option<Basis>,
    /// Sizes and energies.
    pub reports: Vec<BasisReport>,
}

impl FluidBases {
    /// Writes the bases to `path` (the core's array file: `f u g h d` as f64 matrices, the
    /// reports and `key` — what they were built from — in the metadata), for a training that
    /// resumes after its bases.
    pub fn save(&self, path: &Path, key: &str) -> Result<(), FluidError> {
        let mut arrays: Vec<(String, &Tensor)> =
            vec![("f".into(), self.f.matrix()), ("u".into(), self.u.matrix()), ("g".into(), self.g.matrix())];
        arrays.extend(self.h.as_ref().map(|b| ("h".to_string(), b.matrix())));
        arrays.extend(self.d.as_ref().map(|b| ("d".to_string(), b.matrix())));
        let mut meta = HashMap::new();
        meta.insert("format".to_string(), BASES_FORMAT.to_string());
        meta.insert("key".to_string(), key.to_string());
        let reports = serde_json::to_string(&self.reports).map_err(|e| FluidError::State(e.to_string()))?;
        meta.insert("reports".to_string(), reports);
        save_arrays(path, meta, &arrays).map_err(FluidError::from)
    }

    /// Reads bases written by [`Self::save`] if they were built from `key`; `Ok(None)` if the
    /// file holds bases of something else (a training asked for other runs or sizes).
    pub fn load(path: &Path, key: &str) -> Result<Option<Self>, FluidError> {
        let (meta, mut arrays) = load_arrays(path).map_err(FluidError::from)?;
        let fail = |m: String| FluidError::State(format!("{}: {m}", path.display()));
        if meta.get("format").map(String::as_str) != Some(BASES_FORMAT) {
            return Err(fail("not a galerkin fluid bases file".into()));
        }
        if meta.get("key").map(String::as_str) != Some(key) {
            return Ok(None);
        }
        let reports: Vec<BasisReport> = serde_json::from_str(meta.get("reports").map_or("", String::as_str))
            .map_err(|e| fail(format!("reports: {e}")))?;
        let mut basis = |n: &str| -> Result<Option<Basis>, FluidError> {
            arrays.remove(n).map(|m| Basis::new(n, m, 1e-9).map_err(|e| fail(e.to_string()))).transpose()
        };
        let need = |b: Option<Basis>, n: &str| b.ok_or_else(|| fail(format!("basis {n} is missing")));
        Ok(Some(Self {
            f: need(basis("f")?, "f")?,
            u: need(basis("u")?, "u")?,
            g: need(basis("g")?, "g")?,
            h: basis("h")?,
            d: basis("d")?,
            reports,
        }))
    }
}

/// The metadata `format` of a bases file.
const BASES_FORMAT: &str = "galerkin-fluid-bases";

fn truncation(sizes: &BasisSizes, cap: Option<usize>, centred: bool) -> Truncation {
    Truncation { energy: sizes.energy, max_modes: cap.unwrap_or(usize::MAX), centred }
}

fn check_cap(name: &str, cap: Option<usize>, snapshots: usize) -> Result<(), FluidError> {
    match cap {
        Some(0) => Err(FluidError::State(format!("basis {name}: a size of 0 keeps nothing"))),
        Some(m) if m > snapshots => Err(FluidError::State(format!(
            "basis {name}: {m} columns asked, but the training set has only {snapshots} snapshots"
        ))),
        _ => Ok(()),
    }
}

impl FluidBases {
    /// Builds every basis from `set` (see the module docs); `stage(name)` is called as each
    /// basis starts.
    pub fn build(
        set: &TrainingSet,
        sizes: &BasisSizes,
        stage: &mut dyn FnMut(&str),
        ranks: &dyn Communicator,
    ) -> Result<Self, FluidError> {
        if !(sizes.energy > 0.0 && sizes.energy <= 1.0) {
            return Err(FluidError::State(format!("energy {}: must be in (0, 1]", sizes.energy)));
        }
        let k: usize = set.frames().iter().sum();
        for (name, cap) in [("f", sizes.m_f), ("g", sizes.m_g), ("h", sizes.m_h)] {
            check_cap(name, cap, k)?;
        }
        // B_u merges the velocities' and momenta's modes (and the mid-step velocities', one per
        // frame but each run's last).
        let mid_step_frames = if sizes.mid_step { k - set.frames().len().min(k) } else { 0 };
        check_cap("u", sizes.m_u, 2 * k + mid_step_frames)?;
        let mut reports = Vec::new();
        let (mesh, topo) = (set.mesh(), set.topology());

        // The geometry first: the cheapest basis, its folded cells reported before the costly
        // bases are built.
        stage("g");
        let pg = pca_across("g", &mut set.source("g")?, truncation(sizes, sizes.m_g, true), ranks)
            .map_err(FluidError::from)?;
        let projected = check_projected_volumes(set, mesh, &pg.basis)?;
        reports.push(report("g", &pg, projected.note()));

        stage("f");
        let mut pf = pca_across("f", &mut set.source("f")?, truncation(sizes, sizes.m_f, false), ranks)
            .map_err(FluidError::from)?;
        let mut div = relative_divergence(topo, &pf.basis);
        if div > DIVERGENCE_TOLERANCE {
            // Modes of small σ amplify the snapshots' rounding-level divergence (B = S V Σ⁻¹).
            let before = div;
            pf.basis = remove_divergence(topo, &pf.basis)?;
            div = relative_divergence(topo, &pf.basis);
            tracing::info!(before, after = div, "B_f: divergence removed");
        }
        if div > DIVERGENCE_TOLERANCE {
            return Err(FluidError::State(format!(
                "basis f: ‖div B_f‖ is {div:.1e} of ‖B_f‖ (> {DIVERGENCE_TOLERANCE:e}): the flux snapshots are not divergence-free"
            )));
        }
        reports.push(report("f", &pf, format!("‖div B_f‖/‖B_f‖ = {div:.1e}")));

        stage("u");
        let pu = pca_across("u", &mut set.source("u")?, truncation(sizes, sizes.m_u, false), ranks)
            .map_err(FluidError::from)?;
        let pp = pca_across("p", &mut set.source("p")?, truncation(sizes, sizes.m_u, false), ranks)
            .map_err(FluidError::from)?;
        let mid = if sizes.mid_step {
            stage("u (mid-step)");
            let (mut source, _file) = advected_velocities(set)?;
            Some(
                pca_across("u mid-step", &mut source, truncation(sizes, sizes.m_u, false), ranks)
                    .map_err(FluidError::from)?,
            )
        } else {
            None
        };
        let mut parts = vec![&pu.basis, &pp.basis];
        parts.extend(mid.as_ref().map(|m| &m.basis));
        let u = interleave_merge("u", &parts, sizes.m_u)?;
        let energy = mid.as_ref().map_or(1.0, |m| m.energy).min(pu.energy).min(pp.energy);
        let mut note = format!(
            "B_u = B_p: {} velocity and {} momentum modes (energy {:.6} and {:.6})",
            pu.basis.reduced_dim(),
            pp.basis.reduced_dim(),
            pu.energy,
            pp.energy
        );
        if let Some(m) = &mid {
            note += &format!(" and {} mid-step modes (energy {:.6})", m.basis.reduced_dim(), m.energy);
        }
        note += " interleaved";
        reports.push(BasisReport {
            name: "u".into(),
            full: u.full_dim(),
            columns: u.reduced_dim(),
            energy,
            note,
        });

        stage("h");
        let h = if any_nonzero(&mut set.source("h")?)? {
            let ph = pca_across("h", &mut set.source("h")?, truncation(sizes, sizes.m_h, false), ranks)
                .map_err(FluidError::from)?;
            reports.push(report("h", &ph, String::new()));
            Some(ph.basis)
        } else {
            reports.push(BasisReport {
                name: "h".into(),
                full: topo.face_count(),
                columns: 0,
                energy: 1.0,
                note: "no run moves its mesh: no induced flux".into(),
            });
            None
        };

        stage("d");
        let d = constraint_basis(topo, &pf.basis, h.as_ref())?;
        reports.push(BasisReport {
            name: "d".into(),
            full: topo.boundary_faces().len(),
            columns: d.as_ref().map_or(0, Basis::reduced_dim),
            energy: 1.0,
            note: format!(
                "rank of D[B_f, B_h] (singular values > {CONSTRAINT_RANK_TOLERANCE:e}) of {} columns",
                pf.basis.reduced_dim() + h.as_ref().map_or(0, Basis::reduced_dim)
            ),
        });
        for r in &reports {
            tracing::info!(basis = %r.name, full = r.full, columns = r.columns, energy = r.energy, note = %r.note, "basis");
        }
        Ok(Self { f: pf.basis, u, g: pg.basis, h, d, reports })
    }
}

fn report(name: &str, p: &Pca, note: String) -> BasisReport {
    BasisReport {
        name: name.into(),
        full: p.basis.full_dim(),
        columns: p.basis.reduced_dim(),
        energy: p.energy,
        note,
    }
}

/// `‖div B‖_F / ‖B‖_F` of a flux basis.
pub fn relative_divergence(topo: &Topology, b: &Basis) -> f64 {
    let (n, m) = (b.full_dim(), b.reduced_dim());
    let data = b.matrix().data();
    let mut num = 0.0;
    let mut col = vec![0.0; n];
    for j in 0..m {
        for i in 0..n {
            col[i] = data[i * m + j];
        }
        num += divergence(topo, &col).iter().map(|x| x * x).sum::<f64>();
    }
    let den: f64 = data.iter().map(|x| x * x).sum();
    (num / den.max(f64::MIN_POSITIVE)).sqrt()
}

/// Each column of `b` minus its divergent part, `f − divᵀ(div divᵀ)⁻¹ div f` (the Euclidean
/// projection onto divergence-free fluxes; `div divᵀ` is the cells' graph Laplacian with the
/// boundary faces on its diagonal, solved by multigrid-preconditioned CG), re-orthonormalised.
pub fn remove_divergence(topo: &Topology, b: &Basis) -> Result<Basis, FluidError> {
    use crate::tensor::amg::{Amg, Kernel};
    use crate::tensor::CsrMatrix;
    let (nc, nf, d) = (topo.cell_count(), topo.face_count(), topo.dim());
    let mut triplets = Vec::with_capacity(nc * (d + 1));
    for c in 0..nc {
        for l in 0..=d {
            triplets.push((c, topo.cell_face(c, l), topo.sign(c, l)));
        }
    }
    let div = CsrMatrix::from_triplets(nc, nf, &triplets);
    let divt = div.transpose();
    let a = div.matmul(&divt);
    let kernel = if topo.boundary_faces().is_empty() { Kernel::Exact } else { Kernel::Near };
    let amg = Amg::new(&a, &vec![1.0; nc], kernel).map_err(|e| FluidError::State(e.to_string()))?;
    let m = b.reduced_dim();
    let mut data = b.matrix().data().to_vec();
    let mut col = vec![0.0; nf];
    for j in 0..m {
        for i in 0..nf {
            col[i] = data[i * m + j];
        }
        let rhs = div.mul(&col);
        let mut phi = vec![0.0; nc];
        let target = 1e-15 * rhs.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-300) + 1e-16;
        let _ = amg.solve(&a, &rhs, &mut phi, target, 2000);
        let correction = divt.mul(&phi);
        for i in 0..nf {
            data[i * m + j] -= correction[i];
        }
    }
    Basis::orthonormalize("f", &Tensor::from_vec(&[nf, m], data).expect("n_f × m")).map_err(FluidError::from)
}

/// Columns of `a` and `b` interleaved (a₁, b₁, a₂, b₂, …), orthonormalised, at most `cap`.
fn interleave_merge(name: &str, parts: &[&Basis], cap: Option<usize>) -> Result<Basis, FluidError> {
    let n = parts[0].full_dim();
    let widest = parts.iter().map(|b| b.reduced_dim()).max().unwrap_or(0);
    // Column j of every part, then column j + 1 of every part, …
    let order: Vec<(usize, usize)> = (0..widest)
        .flat_map(|j| (0..parts.len()).map(move |p| (p, j)))
        .filter(|&(p, j)| j < parts[p].reduced_dim())
        .collect();
    let k = order.len();
    let mut data = vec![0.0; n * k];
    for (c, &(p, j)) in order.iter().enumerate() {
        let (src, m) = (parts[p].matrix().data(), parts[p].reduced_dim());
        for i in 0..n {
            data[i * k + c] = src[i * m + j];
        }
    }
    // Gram–Schmidt stops at the cap: the first m columns of the whole merged basis.
    let columns = Tensor::from_vec(&[n, k], data).expect("n×k");
    Basis::orthonormalize_at_most(name, &columns, cap.unwrap_or(usize::MAX)).map_err(FluidError::from)
}

/// Every training frame's mid-step velocity — the full solver's advection and diffusion of the
/// frame's velocity over the frame, from its geometry to the next frame's, before the
/// projection ([`crate::fluid::FluidSolver::advect`]) — written frame after frame to a
/// temporary file (returned with the source: the file lives while it does) and streamed to
/// the PCA from there. One advection per training frame but a run's last.
pub fn advected_velocities(
    set: &TrainingSet,
) -> Result<(crate::fluid::snapshots::FrameSnapshots, tempfile::NamedTempFile), FluidError> {
    use std::io::Write;
    let mut solver =
        crate::fluid::FluidSolver::new(set.mesh().clone(), set.topology().clone(), *set.params())?;
    let mut file = tempfile::NamedTempFile::new()
        .map_err(|e| FluidError::State(format!("a temporary file for the mid-step velocities: {e}")))?;
    let path = file.path().to_path_buf();
    let write_error = |e: std::io::Error| FluidError::File { path: path.clone(), message: e.to_string() };
    let (mut frames, mut len) = (0, 0);
    for run in set.runs() {
        let n = run.meta().frames;
        if n < 2 {
            continue;
        }
        // Each geometry is read once: frame k's next is frame k + 1's own.
        let mut g = run.frame("g", 0)?;
        for k in 0..n - 1 {
            let g_next = run.frame("g", k + 1)?;
            let state = crate::fluid::FluidState { g, u: run.frame("u", k)?, f: run.frame("f", k)? };
            let advected = solver.advect(&state, &g_next, k)?;
            g = g_next;
            len = advected.u.len();
            let bytes: Vec<u8> = advected.u.iter().flat_map(|v| v.to_le_bytes()).collect();
            file.write_all(&bytes).map_err(write_error)?;
            frames += 1;
        }
    }
    file.flush().map_err(write_error)?;
    if frames == 0 {
        return Err(FluidError::State(
            "mid-step velocities need training runs of at least two frames".into(),
        ));
    }
    let reader = file.reopen().map_err(write_error)?;
    Ok((crate::fluid::snapshots::FrameSnapshots::over(path, reader, len, frames), file))
}

/// How well a geometry basis holds the training frames: the worst relative geometry error
/// `‖g − B_g B_gᵀ g‖ / ‖g‖`, and the cells the projected geometry folds (non-positive volume).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProjectedGeometry {
    /// Worst relative geometry error over the training frames.
    pub worst_error: f64,
    /// Training frames whose projected geometry folds at least one cell.
    pub folding_frames: usize,
    /// The most cells folded in one frame.
    pub most_folded: usize,
    /// Where the most cells fold: the run's directory, the frame, its most negative cell with
    /// the projected and the true volume.
    pub worst: Option<(String, usize, usize, f64, f64)>,
}

impl ProjectedGeometry {
    /// One line for the basis report.
    pub fn note(&self) -> String {
        let mut note =
            format!("mean first; worst projected-geometry error {:.1e} relative", self.worst_error);
        if let Some((run, frame, cell, v, truth)) = &self.worst {
            note += &format!(
                "; the projected geometry folds cells in {} frames (at most {} cells: {run} frame {frame}, cell {cell} volume {v:.2e}, truly {truth:.2e})",
                self.folding_frames, self.most_folded
            );
        }
        note
    }
}

/// Projects every training frame's geometry onto `bg` and measures what it loses
/// ([`ProjectedGeometry`]). A folded cell is not refused here: the reduced model sees the
/// geometry only through `V̂(ĝ)` and `P̂ ⊗ ĝ` (seed 000 §6.2), and the paper's own eagle
/// (m_g = 7 from an inversion-free full animation, §6.1) keeps no more; what must hold is
/// that `V̂(ĝ)` stays positive definite at every training frame, which the training checks
/// once the tensors are premultiplied ([`super::model::ReducedFluidModel::check_trajectories`]).
fn check_projected_volumes(
    set: &TrainingSet,
    mesh: &SimplexMesh,
    bg: &Basis,
) -> Result<ProjectedGeometry, FluidError> {
    let mut out = ProjectedGeometry::default();
    for (run, path) in set.runs().iter().zip(set.paths()) {
        for frame in 0..run.meta().frames {
            let g = run.frame("g", frame)?;
            let projected = bg.lift(&bg.project(&g));
            let err = g.iter().zip(&projected).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt()
                / g.iter().map(|a| a * a).sum::<f64>().sqrt().max(f64::MIN_POSITIVE);
            out.worst_error = out.worst_error.max(err);
            let vols = mesh.volumes_at(&projected);
            let folded =
                vols.iter().filter(|v| v.partial_cmp(&&0.0) != Some(std::cmp::Ordering::Greater)).count();
            if folded == 0 {
                continue;
            }
            out.folding_frames += 1;
            if folded > out.most_folded {
                out.most_folded = folded;
                let (c, v) = vols
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1.total_cmp(b.1))
                    .map(|(c, &v)| (c, v))
                    .unwrap_or((0, 0.0));
                let truth = crate::mesh::geometry::signed_volume(mesh.dim(), &mesh.cell_points_at(&g, c));
                out.worst = Some((path.display().to_string(), frame, c, v, truth));
            }
        }
    }
    if let Some((run, frame, cell, _, _)) = &out.worst {
        tracing::warn!(
            "basis g: the projected geometry folds cells in {} training frames (at most {} cells, {run} frame {frame}, cell {cell}); the model is kept if V̂(ĝ) stays positive definite",
            out.folding_frames,
            out.most_folded
        );
    }
    Ok(out)
}

fn any_nonzero(source: &mut impl SnapshotSource) -> Result<bool, FluidError> {
    let n = source.dim();
    let mut start = 0;
    while start < n {
        let end = (start + 4096).min(n);
        let block = source.rows(start..end).map_err(FluidError::from)?;
        if block.data().iter().any(|v| *v != 0.0) {
            return Ok(true);
        }
        start = end;
    }
    Ok(false)
}

/// The boundary rows of `[B_f, B_h]`, `D [B_f, B_h]`: (row-major n_b × k values, n_b, k).
pub fn boundary_rows(topo: &Topology, bf: &Basis, bh: Option<&Basis>) -> (Vec<f64>, usize, usize) {
    let boundary = topo.boundary_faces();
    let nb = boundary.len();
    let mf = bf.reduced_dim();
    let mh = bh.map_or(0, Basis::reduced_dim);
    let k = mf + mh;
    let mut m = vec![0.0; nb * k];
    for (row, &face) in boundary.iter().enumerate() {
        let f = face as usize;
        m[row * k..row * k + mf].copy_from_slice(&bf.matrix().data()[f * mf..(f + 1) * mf]);
        if let Some(h) = bh {
            m[row * k + mf..(row + 1) * k].copy_from_slice(&h.matrix().data()[f * mh..(f + 1) * mh]);
        }
    }
    (m, nb, k)
}

/// `B_d`: an orthonormal basis of the range of `D [B_f, B_h]` (see the module docs).
pub fn constraint_basis(
    topo: &Topology,
    bf: &Basis,
    bh: Option<&Basis>,
) -> Result<Option<Basis>, FluidError> {
    let (m, nb, k) = boundary_rows(topo, bf, bh);
    if nb == 0 {
        return Ok(None);
    }
    // The left singular vectors of M whose singular values are not rounding.
    let mat = faer::Mat::from_fn(nb, k, |i, j| m[i * k + j]);
    let svd =
        mat.thin_svd().map_err(|e| FluidError::State(format!("constraint reduction: SVD failed: {e:?}")))?;
    let s = svd.S().column_vector();
    let r = (0..s.nrows()).filter(|&i| s[i] > CONSTRAINT_RANK_TOLERANCE).count();
    if r == 0 {
        return Ok(None);
    }
    let u = svd.U();
    let cols: Vec<f64> = (0..nb).flat_map(|i| (0..r).map(move |j| u[(i, j)])).collect();
    let basis = Basis::orthonormalize("d", &Tensor::from_vec(&[nb, r], cols).expect("n_b×r"))
        .map_err(FluidError::from)?;
    Ok(Some(basis))
}
