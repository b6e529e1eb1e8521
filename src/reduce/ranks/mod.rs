//! The communication seam of the precompute: ranks that each hold a share of the rows of the
//! snapshot matrices and of a tensor's chunks, and meet in a few collective operations — the
//! sharded PCA's one allreduce of Gram matrices ([`super::pca`], [`super::snapshot_grams`]),
//! the sharded premultiplication's one reduction of the small reduced tensors
//! ([`super::premultiply_streamed_together`]). The paper ran its premultiplication on a
//! 110-node cluster (seed 000 §6.3, §9); this is what lets ours.
//!
//! Three implementations, and nothing above the core knows which one runs:
//! - [`SingleRank`]: the default build, no MPI;
//! - [`ThreadRanks`]: threads as ranks, for tests without MPI;
//! - `MpiRanks` (cargo feature `mpi`): MPI through the `mpi` crate (rsmpi) on the system's
//!   OpenMPI.
//!
//! Sums are **deterministic**: every implementation adds the ranks' contributions in rank order
//! (`((x₀ + x₁) + x₂) + …`), so a run is reproducible bit for bit at a given number of ranks
//! and differs between rank counts only by the rounding of a differently split sum.

use std::ops::Range;

mod threads;

#[cfg(feature = "mpi")]
mod mpi;

#[cfg(feature = "mpi")]
pub use self::mpi::{MpiRanks, Summation};
pub use threads::{ThreadRank, ThreadRanks};

/// A collective operation failed, or another rank failed and stopped every rank.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("rank {rank}: {message}")]
pub struct RanksError {
    /// The rank that failed (or, for a transport error, the rank that saw it).
    pub rank: usize,
    /// What went wrong there.
    pub message: String,
}

/// Ranks that meet in collective operations. Every rank calls the same collectives in the same
/// order with the same lengths (a collective's contract; lengths are checked where it is cheap).
pub trait Communicator: Sync {
    /// This rank, `0 ≤ rank < size`.
    fn rank(&self) -> usize;
    /// Number of ranks.
    fn size(&self) -> usize;
    /// Element-wise sum of `values` over every rank, left in `values` on every rank, added in
    /// rank order (deterministic).
    fn allreduce_sum(&self, values: &mut [f64]) -> Result<(), RanksError>;
    /// `bytes` of rank `root` copied to every rank (the others' are replaced).
    fn broadcast(&self, bytes: &mut Vec<u8>, root: usize) -> Result<(), RanksError>;
    /// Every rank's `bytes`, in rank order, at `root`; `None` on the other ranks.
    fn gather(&self, bytes: &[u8], root: usize) -> Result<Option<Vec<Vec<u8>>>, RanksError>;
    /// This rank failed with `message`: stop every rank with it (threads wake the others with
    /// the message; MPI aborts the job after printing it). Returns when the others were told.
    fn fail(&self, message: &str);

    /// Every rank's `bytes`, in rank order, on every rank (a gather then a broadcast).
    fn all_gather(&self, bytes: &[u8]) -> Result<Vec<Vec<u8>>, RanksError> {
        let gathered = self.gather(bytes, 0)?;
        let mut packed = gathered.map(|parts| pack(&parts)).unwrap_or_default();
        self.broadcast(&mut packed, 0)?;
        unpack(&packed, self.size()).map_err(|message| RanksError { rank: self.rank(), message })
    }

    /// This rank's share of `n` items split into contiguous ranges, in rank order, whose
    /// lengths differ by at most one (the first `n mod size` ranks take one more).
    fn share(&self, n: usize) -> Range<usize> {
        partition(n, self.size(), self.rank())
    }

    /// Bytes of payload this rank has put into collectives so far (its contributions to
    /// allreduces and gathers, its broadcasts as root): what its share of the work costs in
    /// communication. 0 on one rank.
    fn bytes_sent(&self) -> u64 {
        0
    }

    /// Waits until every rank has arrived here (an allreduce of nothing; a failed rank stops
    /// the others with its message).
    fn barrier(&self) -> Result<(), RanksError> {
        self.allreduce_sum(&mut [0.0])
    }

    /// Whether this rank writes files and shows progress and logs (rank 0).
    fn is_root(&self) -> bool {
        self.rank() == 0
    }
}

/// Part `rank` of `n` items split over `size` ranks: contiguous, in order, lengths differing by
/// at most one.
pub fn partition(n: usize, size: usize, rank: usize) -> Range<usize> {
    let size = size.max(1);
    let (base, extra) = (n / size, n % size);
    let start = rank * base + rank.min(extra);
    let len = base + usize::from(rank < extra);
    start.min(n)..(start + len).min(n)
}

/// Sums `parts` element-wise over `ranks` in one allreduce (their lengths must agree between
/// ranks); nothing to do on one rank.
pub(crate) fn allreduce_parts(
    ranks: &dyn Communicator,
    parts: &mut [&mut [f64]],
    what: &str,
) -> Result<(), crate::reduce::ReduceError> {
    if ranks.size() == 1 {
        return Ok(());
    }
    let mut flat: Vec<f64> = parts.iter().flat_map(|p| p.iter().copied()).collect();
    ranks.allreduce_sum(&mut flat).map_err(|cause| crate::reduce::ReduceError::Ranks {
        context: format!("summing {what} over ranks"),
        cause,
    })?;
    let mut rest = flat.as_slice();
    for p in parts.iter_mut() {
        let (mine, tail) = rest.split_at(p.len());
        p.copy_from_slice(mine);
        rest = tail;
    }
    Ok(())
}

/// One rank alone: every collective is the identity. The default.
#[derive(Clone, Copy, Debug, Default)]
pub struct SingleRank;

impl Communicator for SingleRank {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn allreduce_sum(&self, _values: &mut [f64]) -> Result<(), RanksError> {
        Ok(())
    }
    fn broadcast(&self, _bytes: &mut Vec<u8>, _root: usize) -> Result<(), RanksError> {
        Ok(())
    }
    fn gather(&self, bytes: &[u8], _root: usize) -> Result<Option<Vec<Vec<u8>>>, RanksError> {
        Ok(Some(vec![bytes.to_vec()]))
    }
    fn fail(&self, _message: &str) {}
}

/// The one rank, for options whose default is to run alone.
pub(crate) static SINGLE_RANK: SingleRank = SingleRank;

/// Sums the ranks' contributions (`parts[r]`, each `len` values) into `out` in rank order.
pub(crate) fn sum_in_rank_order(parts: &[&[f64]], out: &mut [f64]) {
    out.fill(0.0);
    for part in parts {
        for (o, v) in out.iter_mut().zip(*part) {
            *o += v;
        }
    }
}

/// Values as little-endian bytes (what crosses between ranks).
pub(crate) fn f64_bytes(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Little-endian bytes back to values; an error if the length is not a whole number of them.
pub(crate) fn bytes_f64(bytes: &[u8]) -> Result<Vec<f64>, String> {
    if !bytes.len().is_multiple_of(8) {
        return Err(format!("{} bytes are not a whole number of f64 values", bytes.len()));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
        .collect())
}

/// Several byte strings as one: each length (u64 LE) then its bytes.
fn pack(parts: &[Vec<u8>]) -> Vec<u8> {
    let mut out = Vec::with_capacity(parts.iter().map(|p| p.len() + 8).sum());
    for p in parts {
        out.extend_from_slice(&(p.len() as u64).to_le_bytes());
        out.extend_from_slice(p);
    }
    out
}

/// [`pack`] undone, expecting `count` parts.
fn unpack(mut bytes: &[u8], count: usize) -> Result<Vec<Vec<u8>>, String> {
    let mut parts = Vec::with_capacity(count);
    for i in 0..count {
        let (len, rest) = bytes
            .split_first_chunk::<8>()
            .ok_or_else(|| format!("gathered bytes end before part {i} of {count}"))?;
        let len =
            usize::try_from(u64::from_le_bytes(*len)).map_err(|_| "a part longer than memory".to_string())?;
        if len > rest.len() {
            return Err(format!("part {i} declares {len} bytes, {} remain", rest.len()));
        }
        parts.push(rest[..len].to_vec());
        bytes = &rest[len..];
    }
    if !bytes.is_empty() {
        return Err(format!("{} bytes left after {count} parts", bytes.len()));
    }
    Ok(parts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partitions_cover_in_order_and_differ_by_at_most_one() {
        for n in [0, 1, 5, 7, 100] {
            for size in 1..6 {
                let parts: Vec<Range<usize>> = (0..size).map(|r| partition(n, size, r)).collect();
                assert_eq!(parts[0].start, 0);
                assert_eq!(parts[size - 1].end, n);
                for w in parts.windows(2) {
                    assert_eq!(w[0].end, w[1].start);
                }
                let lens: Vec<usize> = parts.iter().map(|p| p.len()).collect();
                assert!(
                    lens.iter().max().unwrap() - lens.iter().min().unwrap() <= 1,
                    "{n} over {size}: {lens:?}"
                );
            }
        }
    }

    #[test]
    fn packed_parts_round_trip_and_truncation_is_refused() {
        let parts = vec![vec![1, 2, 3], vec![], vec![9; 20]];
        let packed = pack(&parts);
        assert_eq!(unpack(&packed, 3).unwrap(), parts);
        assert!(unpack(&packed[..packed.len() - 1], 3).is_err());
        assert!(unpack(&packed, 2).is_err());
    }
}
