//! MPI ranks through the `mpi` crate (rsmpi) on the system's MPI (Debian 12: OpenMPI 4.1).
//! Built with the cargo feature `mpi`; a process started by `mpirun` joins `MPI_COMM_WORLD`.
//!
//! MPI counts are 32-bit: every transfer is split into pieces of at most 2³⁰ elements. Sums
//! are in rank order by default ([`Summation::RankOrder`]: gathered on rank 0, added there,
//! broadcast), so a result does not depend on MPI's choice of reduction tree;
//! [`Summation::Native`] uses `MPI_Allreduce` instead.

use std::sync::atomic::{AtomicU64, Ordering};
use std::thread::ThreadId;

use mpi::collective::SystemOperation;
use mpi::topology::Communicator as _;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::{sum_in_rank_order, Communicator, RanksError};

/// Largest number of elements in one MPI call (counts are `int`).
const PIECE: usize = 1 << 30;

/// How [`MpiRanks::allreduce_sum`](Communicator::allreduce_sum) adds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Summation {
    /// Gathered on rank 0 and added in rank order, then broadcast: reproducible bit for bit.
    #[default]
    RankOrder,
    /// `MPI_Allreduce` (its own order and tree): faster for large sums at many ranks.
    Native,
}

/// The ranks of `MPI_COMM_WORLD`. MPI is finalised when this is dropped.
pub struct MpiRanks {
    world: SimpleCommunicator,
    rank: usize,
    size: usize,
    summation: Summation,
    owner: ThreadId,
    sent: AtomicU64,
    // Dropped last: finalises MPI.
    _universe: mpi::environment::Universe,
}

// SAFETY: MPI is initialised at MPI_THREAD_FUNNELED — only the initialising thread may call it —
// and every method of this type that calls MPI first checks that it runs on that thread
// (`on_owner`), returning an error otherwise; the other fields are plain data.
unsafe impl Sync for MpiRanks {}

impl MpiRanks {
    /// Joins `MPI_COMM_WORLD` if this process was started by an MPI launcher (`mpirun` sets
    /// `OMPI_COMM_WORLD_SIZE`, or `PMI_SIZE` / `PMIX_RANK` for others); `None` when it was
    /// not, so that a plain run stays one rank without initialising MPI.
    pub fn from_launcher(summation: Summation) -> Result<Option<Self>, RanksError> {
        let launched =
            ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"].iter().any(|v| std::env::var_os(v).is_some());
        if !launched {
            return Ok(None);
        }
        let Some((universe, _level)) = mpi::initialize_with_threading(mpi::Threading::Funneled) else {
            return Err(RanksError { rank: 0, message: "MPI was already initialised".into() });
        };
        let world = universe.world();
        let (rank, size) = (world.rank() as usize, world.size() as usize);
        Ok(Some(Self {
            world,
            rank,
            size,
            summation,
            owner: std::thread::current().id(),
            sent: AtomicU64::new(0),
            _universe: universe,
        }))
    }

    fn on_owner(&self) -> Result<(), RanksError> {
        if std::thread::current().id() == self.owner {
            Ok(())
        } else {
            Err(RanksError {
                rank: self.rank,
                message: "MPI called from a thread that did not initialise it".into(),
            })
        }
    }

    fn broadcast_len(&self, len: &mut u64, root: usize) {
        self.world.process_at_rank(root as i32).broadcast_into(len);
    }
}

impl Communicator for MpiRanks {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.size
    }

    fn allreduce_sum(&self, values: &mut [f64]) -> Result<(), RanksError> {
        self.on_owner()?;
        self.sent.fetch_add(8 * values.len() as u64, Ordering::Relaxed);
        let mut len = values.len() as u64;
        self.broadcast_len(&mut len, 0);
        if len != values.len() as u64 {
            return Err(RanksError {
                rank: self.rank,
                message: format!("allreduce of {} values, rank 0 has {len}", values.len()),
            });
        }
        for piece in values.chunks_mut(PIECE) {
            match self.summation {
                Summation::Native => {
                    let send = piece.to_vec();
                    self.world.all_reduce_into(&send[..], piece, SystemOperation::sum());
                }
                Summation::RankOrder => {
                    let root = self.world.process_at_rank(0);
                    if self.rank == 0 {
                        let mut all = vec![0.0; piece.len() * self.size];
                        root.gather_into_root(&piece[..], &mut all[..]);
                        let parts: Vec<&[f64]> = all.chunks_exact(piece.len().max(1)).collect();
                        sum_in_rank_order(&parts, piece);
                    } else {
                        root.gather_into(&piece[..]);
                    }
                    root.broadcast_into(piece);
                }
            }
        }
        Ok(())
    }

    fn broadcast(&self, bytes: &mut Vec<u8>, root: usize) -> Result<(), RanksError> {
        self.on_owner()?;
        let mut len = bytes.len() as u64;
        self.broadcast_len(&mut len, root);
        let len = usize::try_from(len)
            .map_err(|_| RanksError { rank: root, message: format!("a broadcast of {len} bytes") })?;
        bytes.resize(len, 0);
        if self.rank == root {
            self.sent.fetch_add(len as u64, Ordering::Relaxed);
        }
        let from = self.world.process_at_rank(root as i32);
        for piece in bytes.chunks_mut(PIECE) {
            from.broadcast_into(piece);
        }
        Ok(())
    }

    fn gather(&self, bytes: &[u8], root: usize) -> Result<Option<Vec<Vec<u8>>>, RanksError> {
        self.on_owner()?;
        let at_root = self.world.process_at_rank(root as i32);
        let len = bytes.len() as u64;
        self.sent.fetch_add(len, Ordering::Relaxed);
        if self.rank != root {
            at_root.gather_into(&len);
            for piece in bytes.chunks(PIECE) {
                at_root.send(piece);
            }
            return Ok(None);
        }
        let mut lens = vec![0u64; self.size];
        at_root.gather_into_root(&len, &mut lens[..]);
        let mut parts = Vec::with_capacity(self.size);
        for (r, &l) in lens.iter().enumerate() {
            if r == root {
                parts.push(bytes.to_vec());
                continue;
            }
            let l = usize::try_from(l)
                .map_err(|_| RanksError { rank: r, message: format!("a gather of {l} bytes") })?;
            let mut part = vec![0u8; l];
            let from = self.world.process_at_rank(r as i32);
            for piece in part.chunks_mut(PIECE) {
                from.receive_into(piece);
            }
            parts.push(part);
        }
        Ok(Some(parts))
    }

    fn bytes_sent(&self) -> u64 {
        self.sent.load(Ordering::Relaxed)
    }

    fn fail(&self, message: &str) {
        eprintln!("galerkin: rank {} of {}: {message}", self.rank, self.size);
        eprintln!("galerkin: stopping every rank");
        self.world.abort(1)
    }
}
