//! The training configurations over ranks: each rank solves its contiguous share of the
//! samples in full ([`super::train::solve_configurations`]) and every rank receives every
//! solved configuration (one all-gather), since each rank's share of the pair quantities'
//! rows (a range of faces `i`, pairs `i n + j`) needs every configuration's values there.
//!
//! A configuration crosses between ranks as little-endian bytes: a header of counts, then its
//! parameters, vertex positions, face geometry, visibility words, emission and radiosity. The
//! reader checks every count against the bytes that remain before allocating from it.

use super::error::RadiosityError;
use super::mesh::FaceGeometry;
use super::near_correction::NearCorrection;
use super::train::{solve_configurations, Configuration, DesignSpace, TrainOptions};
use crate::reduce::Communicator;
use glam::DVec3;

/// Solves the configurations at `params` shared over `ranks` and gathers them all on every
/// rank, in the order of `params`. `progress` is called with this rank's solves so far.
pub fn solve_configurations_across(
    space: &dyn DesignSpace,
    params: &[Vec<f64>],
    options: &TrainOptions,
    progress: &(dyn Fn(usize) + Sync),
    ranks: &dyn Communicator,
) -> Result<Vec<Configuration>, RadiosityError> {
    let share = ranks.share(params.len());
    let mine = solve_configurations(space, &params[share], options, progress)?;
    if ranks.size() == 1 {
        return Ok(mine);
    }
    let mut bytes = Vec::new();
    for c in &mine {
        encode(c, &mut bytes);
    }
    let parts = ranks
        .all_gather(&bytes)
        .map_err(|cause| RadiosityError::Solve(format!("gathering the solved configurations: {cause}")))?;
    let mut all = Vec::with_capacity(params.len());
    for (rank, part) in parts.iter().enumerate() {
        all.extend(decode(part, &format!("rank {rank}"))?);
    }
    if all.len() != params.len() {
        return Err(RadiosityError::Solve(format!(
            "the ranks solved {} configurations of {}",
            all.len(),
            params.len()
        )));
    }
    Ok(all)
}

fn put_f64s(out: &mut Vec<u8>, values: impl IntoIterator<Item = f64>) {
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

fn vec3s(v: &[DVec3]) -> impl Iterator<Item = f64> + '_ {
    v.iter().flat_map(|p| p.to_array())
}

/// Appends `c` to `out` (the bytes that cross between ranks and that a training's work
/// directory keeps per solved configuration, [`super::train_stages`]).
pub(crate) fn encode(c: &Configuration, out: &mut Vec<u8>) {
    let n = c.geometry.areas.len();
    for count in [c.params.len(), c.g.len(), n, c.visibility.len(), c.near_correction.len()] {
        out.extend_from_slice(&(count as u64).to_le_bytes());
    }
    put_f64s(out, c.params.iter().copied());
    put_f64s(out, c.g.iter().copied());
    put_f64s(out, vec3s(&c.geometry.centroids));
    put_f64s(out, vec3s(&c.geometry.normals));
    put_f64s(out, c.geometry.areas.iter().copied());
    put_f64s(out, c.geometry.edge_squares.iter().copied());
    for w in &c.visibility {
        out.extend_from_slice(&w.to_le_bytes());
    }
    put_f64s(out, c.emission.iter().flatten().copied());
    put_f64s(out, c.radiosity.iter().flatten().copied());
    for &(k, delta) in c.near_correction.iter() {
        out.extend_from_slice(&(u64::from(k) | u64::from(delta.to_bits()) << 32).to_le_bytes());
    }
}

/// Every configuration [`encode`] wrote into `bytes`; errors name `source` (a rank, a file).
pub(crate) fn decode(bytes: &[u8], source: &str) -> Result<Vec<Configuration>, RadiosityError> {
    let mut reader = Reader { bytes, source };
    let mut all = Vec::new();
    while !reader.bytes.is_empty() {
        all.push(reader.configuration()?);
    }
    Ok(all)
}

struct Reader<'a> {
    bytes: &'a [u8],
    source: &'a str,
}

impl Reader<'_> {
    fn bad(&self, what: &str) -> RadiosityError {
        RadiosityError::Solve(format!("configuration bytes from {}: {what}", self.source))
    }

    fn word(&mut self) -> Result<u64, RadiosityError> {
        let (w, rest) = self.bytes.split_first_chunk::<8>().ok_or_else(|| self.bad("they end early"))?;
        self.bytes = rest;
        Ok(u64::from_le_bytes(*w))
    }

    /// `count` words, refused before allocating if fewer bytes remain.
    fn words(&mut self, count: u64) -> Result<Vec<u64>, RadiosityError> {
        let count = usize::try_from(count).map_err(|_| self.bad("a count longer than memory"))?;
        if count.checked_mul(8).is_none_or(|b| b > self.bytes.len()) {
            return Err(self.bad(&format!("{count} values declared, {} bytes remain", self.bytes.len())));
        }
        (0..count).map(|_| self.word()).collect()
    }

    fn f64s(&mut self, count: u64) -> Result<Vec<f64>, RadiosityError> {
        Ok(self.words(count)?.into_iter().map(f64::from_bits).collect())
    }

    fn vec3s(&mut self, count: u64) -> Result<Vec<DVec3>, RadiosityError> {
        let v = self.f64s(count.saturating_mul(3))?;
        Ok(v.chunks_exact(3).map(DVec3::from_slice).collect())
    }

    fn rgbs(&mut self, count: u64) -> Result<Vec<[f64; 3]>, RadiosityError> {
        let v = self.f64s(count.saturating_mul(3))?;
        Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    fn configuration(&mut self) -> Result<Configuration, RadiosityError> {
        let (params, g, n, words) = (self.word()?, self.word()?, self.word()?, self.word()?);
        let corrections = self.word()?;
        Ok(Configuration {
            params: self.f64s(params)?,
            g: self.f64s(g)?,
            geometry: FaceGeometry {
                centroids: self.vec3s(n)?,
                normals: self.vec3s(n)?,
                areas: self.f64s(n)?,
                edge_squares: self.f64s(n)?,
            },
            visibility: self.words(words)?,
            emission: self.rgbs(n)?,
            radiosity: self.rgbs(n)?,
            near_correction: self.near_correction(corrections, n)?,
        })
    }

    /// `count` near-field corrections of `n` faces (pairs `k = n·i + j` with `i < j`).
    fn near_correction(&mut self, count: u64, n: u64) -> Result<NearCorrection, RadiosityError> {
        let entries = self.words(count)?;
        let mut out = Vec::with_capacity(entries.len());
        for w in entries {
            let (k, delta) = (w & 0xFFFF_FFFF, f32::from_bits((w >> 32) as u32));
            if k / n.max(1) >= k % n.max(1) || !delta.is_finite() {
                return Err(self.bad(&format!("near-field correction of pair {k} for {n} faces")));
            }
            out.push((k as u32, delta));
        }
        Ok(out.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn configuration(n: usize, correction: Vec<(u32, f32)>) -> Configuration {
        Configuration {
            params: vec![0.5, 1.5],
            g: (0..9).map(f64::from).collect(),
            geometry: FaceGeometry {
                centroids: vec![DVec3::new(1.0, 2.0, 3.0); n],
                normals: vec![DVec3::Z; n],
                areas: vec![0.25; n],
                edge_squares: vec![1.0; n],
            },
            visibility: vec![0b1011; (n * n).div_ceil(64)],
            emission: vec![[1.0, 0.5, 0.25]; n],
            radiosity: vec![[2.0, 1.0, 0.5]; n],
            near_correction: correction.into(),
        }
    }

    /// A configuration with its near-field correction crosses ranks whole; a correction naming
    /// a pair that is not `i < j` of its faces, or a non-finite value, is refused before it
    /// can reach the tensor `Q`.
    #[test]
    fn configurations_cross_ranks_with_their_near_field_corrections() {
        let n = 3;
        let good = configuration(n, vec![(1, 0.125), (2, -0.5), (5, 1e-3)]);
        let mut bytes = Vec::new();
        encode(&good, &mut bytes);
        let back = Reader { bytes: &bytes, source: "rank 1" }.configuration().expect("read back");
        assert_eq!(back.near_correction, good.near_correction);
        assert_eq!((back.g, back.radiosity, back.visibility), (good.g, good.radiosity, good.visibility));
        // (k = 4: i = j = 1; k = 3: i = 1 > j = 0; k = 9: beyond n²; a NaN.)
        for bad in [vec![(4, 0.1)], vec![(3, 0.1)], vec![(9, 0.1)], vec![(1, f32::NAN)]] {
            let mut bytes = Vec::new();
            encode(&configuration(n, bad.clone()), &mut bytes);
            let e = Reader { bytes: &bytes, source: "rank 2" }.configuration().expect_err("refused");
            assert!(e.to_string().contains("rank 2") && e.to_string().contains("near-field"), "{bad:?}: {e}");
        }
    }
}
