//! Threads as ranks: `size` threads of one process, each with its [`ThreadRank`], meeting in
//! collectives through shared memory — for testing the sharded precompute at 1, 2, 3, 4 ranks
//! without MPI. Every collective is one exchange: each rank deposits its bytes, the last to
//! arrive publishes them all, and each rank takes what the operation needs (a sum in rank
//! order, the root's bytes, or all of them).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};

use super::{bytes_f64, f64_bytes, sum_in_rank_order, Communicator, RanksError};

/// Launches threads as ranks.
pub struct ThreadRanks;

/// One thread's rank.
pub struct ThreadRank {
    rank: usize,
    shared: Arc<Shared>,
    sent: AtomicU64,
}

struct Shared {
    size: usize,
    round: Mutex<Round>,
    arrived: Condvar,
}

#[derive(Default)]
struct Round {
    /// Completed exchanges so far.
    generation: u64,
    /// Contributions of the exchange under way, by rank.
    slots: Vec<Option<Vec<u8>>>,
    /// How many ranks deposited in the exchange under way.
    count: usize,
    /// The last completed exchange's contributions, in rank order.
    published: Arc<Vec<Vec<u8>>>,
    /// The first rank that failed, and its message.
    failed: Option<(usize, String)>,
}

impl ThreadRanks {
    /// Runs `work` on `size` threads, each given its rank; returns each rank's result in rank
    /// order. A rank that returns an error or panics stops the others: their pending and later
    /// collectives return its message.
    pub fn run<T: Send, E: std::fmt::Display + Send>(
        size: usize,
        work: impl Fn(&ThreadRank) -> Result<T, E> + Sync,
    ) -> Vec<Result<T, String>> {
        let size = size.max(1);
        let shared = Arc::new(Shared {
            size,
            round: Mutex::new(Round { slots: vec![None; size], ..Round::default() }),
            arrived: Condvar::new(),
        });
        std::thread::scope(|scope| {
            let handles: Vec<_> = (0..size)
                .map(|rank| {
                    let comm = ThreadRank { rank, shared: shared.clone(), sent: AtomicU64::new(0) };
                    let work = &work;
                    scope.spawn(move || {
                        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(&comm)));
                        match outcome {
                            Ok(Ok(value)) => Ok(value),
                            Ok(Err(e)) => {
                                let message = e.to_string();
                                comm.fail(&message);
                                Err(message)
                            }
                            Err(_) => {
                                let message = "panicked".to_string();
                                comm.fail(&message);
                                Err(message)
                            }
                        }
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|_| Err("the rank's thread could not be joined".into())))
                .collect()
        })
    }
}

impl ThreadRank {
    fn lock(&self) -> MutexGuard<'_, Round> {
        // A rank that panicked while holding the lock left the round consistent (every write
        // under the lock is a single assignment), so the poison is not an error of ours.
        self.shared.round.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn stopped(&self, failed: &(usize, String)) -> RanksError {
        RanksError { rank: failed.0, message: format!("stopped every rank: {}", failed.1) }
    }

    /// Deposits `bytes` and returns every rank's, in rank order, once all have arrived.
    fn exchange(&self, bytes: Vec<u8>) -> Result<Arc<Vec<Vec<u8>>>, RanksError> {
        self.sent.fetch_add(bytes.len() as u64, Ordering::Relaxed);
        let mut round = self.lock();
        if let Some(f) = &round.failed {
            return Err(self.stopped(f));
        }
        let generation = round.generation;
        round.slots[self.rank] = Some(bytes);
        round.count += 1;
        if round.count == self.shared.size {
            let all: Vec<Vec<u8>> = round.slots.iter_mut().map(|s| s.take().unwrap_or_default()).collect();
            round.published = Arc::new(all);
            round.count = 0;
            round.generation += 1;
            self.shared.arrived.notify_all();
            return Ok(round.published.clone());
        }
        while round.generation == generation && round.failed.is_none() {
            round = self.shared.arrived.wait(round).unwrap_or_else(|p| p.into_inner());
        }
        if round.generation == generation {
            let f = round.failed.clone().unwrap_or_default();
            return Err(self.stopped(&f));
        }
        // The next exchange cannot complete without this rank, so `published` is still ours.
        Ok(round.published.clone())
    }
}

impl Communicator for ThreadRank {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.shared.size
    }
    fn allreduce_sum(&self, values: &mut [f64]) -> Result<(), RanksError> {
        let all = self.exchange(f64_bytes(values))?;
        let parts = all
            .iter()
            .enumerate()
            .map(|(r, b)| {
                let v = bytes_f64(b).map_err(|message| RanksError { rank: r, message })?;
                if v.len() != values.len() {
                    return Err(RanksError {
                        rank: r,
                        message: format!(
                            "allreduce of {} values met {} from this rank",
                            values.len(),
                            v.len()
                        ),
                    });
                }
                Ok(v)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let refs: Vec<&[f64]> = parts.iter().map(Vec::as_slice).collect();
        sum_in_rank_order(&refs, values);
        Ok(())
    }
    fn broadcast(&self, bytes: &mut Vec<u8>, root: usize) -> Result<(), RanksError> {
        let mine = if self.rank == root { std::mem::take(bytes) } else { Vec::new() };
        let all = self.exchange(mine)?;
        *bytes = all.get(root).cloned().unwrap_or_default();
        Ok(())
    }
    fn gather(&self, bytes: &[u8], root: usize) -> Result<Option<Vec<Vec<u8>>>, RanksError> {
        let all = self.exchange(bytes.to_vec())?;
        Ok((self.rank == root).then(|| all.as_ref().clone()))
    }
    fn bytes_sent(&self) -> u64 {
        self.sent.load(Ordering::Relaxed)
    }
    fn fail(&self, message: &str) {
        let mut round = self.lock();
        if round.failed.is_none() {
            round.failed = Some((self.rank, message.to_string()));
        }
        self.shared.arrived.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collectives_agree_on_every_rank() {
        for size in 1..=4 {
            let out = ThreadRanks::run(size, |c| {
                let mut v = vec![c.rank() as f64 + 0.5, 1.0];
                c.allreduce_sum(&mut v)?;
                let mut b = if c.rank() == size - 1 { vec![7u8, 8] } else { vec![] };
                c.broadcast(&mut b, size - 1)?;
                let g = c.all_gather(&[c.rank() as u8; 3])?;
                Ok::<_, RanksError>((v, b, g))
            });
            for r in out {
                let (v, b, g) = r.unwrap();
                let want: f64 = (0..size).map(|r| r as f64 + 0.5).sum();
                assert_eq!(v, vec![want, size as f64]);
                assert_eq!(b, vec![7, 8]);
                assert_eq!(g, (0..size).map(|r| vec![r as u8; 3]).collect::<Vec<_>>());
            }
        }
    }

    #[test]
    fn a_failing_rank_stops_the_others_with_its_message() {
        let out = ThreadRanks::run(3, |c| {
            if c.rank() == 1 {
                return Err(RanksError { rank: 1, message: "bad snapshot".into() });
            }
            let mut v = vec![1.0];
            c.allreduce_sum(&mut v)?;
            Ok(v)
        });
        for r in &out {
            let e = r.as_ref().unwrap_err();
            assert!(e.contains("bad snapshot"), "{e}");
        }
    }
}
