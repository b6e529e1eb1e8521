//! The ranks this process runs on: `MPI_COMM_WORLD` when the build has the `mpi` feature and
//! `mpirun` started the process, one rank otherwise.

use anyhow::Result;
use galerkin::reduce::{Communicator, SingleRank};

/// The ranks of this run. Held by `main` for the whole command (MPI is finalised when it is
/// dropped). `GALERKIN_MPI_SUM=native` sums with `MPI_Allreduce` instead of in rank order.
pub fn open() -> Result<Box<dyn Communicator>> {
    #[cfg(feature = "mpi")]
    {
        use galerkin::reduce::ranks::{MpiRanks, Summation};
        let summation = match std::env::var("GALERKIN_MPI_SUM").as_deref() {
            Ok("native") => Summation::Native,
            Ok("rank-order") | Err(_) => Summation::RankOrder,
            Ok(other) => anyhow::bail!("GALERKIN_MPI_SUM={other:?}: expected `rank-order` or `native`"),
        };
        if let Some(ranks) = MpiRanks::from_launcher(summation)? {
            return Ok(Box::new(ranks));
        }
    }
    if std::env::var_os("OMPI_COMM_WORLD_SIZE").is_some_and(|s| s != "1") {
        anyhow::bail!(
            "started by mpirun, but this galerkin was built without MPI: build it with `cargo build --release --features mpi`"
        );
    }
    Ok(Box::new(SingleRank))
}
