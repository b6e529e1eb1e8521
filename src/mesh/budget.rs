//! How large a generated mesh may be: the generators ([`super::stuffing::stuff`],
//! [`super::tunnel::tunnel`]) estimate their cell count from the spacing before they build
//! anything and refuse a mesh past the budget (DESIGN "Limits": every size read from input is
//! checked before anything is allocated from it).
//!
//! The budget a user meets is the machine's: a generated mesh is what the fluid solver
//! simulates (seed 000 §7), so a mesh whose simulation would not fit the machine's memory is
//! refused with the memory it would need. A fuzzer or a test asks for a smaller one
//! ([`CellBudget::cells`]) so that every scene it builds stays quick.

use super::MeshError;

/// Memory the fluid solver holds per cell of a generated mesh, about (measured: 15 GB peak for
/// `fluid simulate` of a 2,179,370-cell stuffed bird scene).
pub const SIMULATION_BYTES_PER_CELL: f64 = 7_000.0;

/// The most cells a generator may build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellBudget {
    cells: f64,
    /// The machine's memory in bytes when the budget comes from it (then errors say so).
    memory: Option<f64>,
}

impl CellBudget {
    /// What this machine can simulate: `MemTotal` / [`SIMULATION_BYTES_PER_CELL`] cells;
    /// unbounded (each generator's own fixed caps still hold) where `/proc/meminfo` cannot be
    /// read.
    pub fn machine() -> Self {
        match crate::limits::memory_total() {
            Some(total) => {
                Self { cells: total as f64 / SIMULATION_BYTES_PER_CELL, memory: Some(total as f64) }
            }
            None => Self { cells: f64::INFINITY, memory: None },
        }
    }

    /// At most `cells` cells, whatever the machine (fuzzing, tests, a host that wants small
    /// scenes only).
    pub fn cells(cells: f64) -> Self {
        Self { cells, memory: None }
    }

    /// The most cells allowed.
    pub fn max_cells(&self) -> f64 {
        self.cells
    }

    /// Refuses an estimate of `cells` cells past the budget; `what` names the generator and
    /// its setting ("isosurface stuffing at spacing 0.01"), `knob` the setting to raise.
    pub fn check(&self, what: &str, cells: f64, knob: &str) -> Result<(), MeshError> {
        if cells <= self.cells {
            return Ok(());
        }
        Err(MeshError::Generation(match self.memory {
            Some(total) => format!(
                "{what}: up to about {cells:.3e} cells, which would need about {:.0} GB to simulate (about {:.0} kB a cell); this machine has {:.0} GB: raise {knob}",
                cells * SIMULATION_BYTES_PER_CELL / 1e9,
                SIMULATION_BYTES_PER_CELL / 1e3,
                total / 1e9
            ),
            None => format!(
                "{what}: up to about {cells:.3e} cells, past the budget of {:.3e}: raise {knob}",
                self.cells
            ),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_past_the_budget_are_refused_naming_the_knob() {
        let small = CellBudget::cells(1000.0);
        assert!(small.check("a generator", 1000.0, "the spacing").is_ok());
        let e = small.check("a generator", 1001.0, "the spacing").unwrap_err().to_string();
        assert!(e.contains("a generator") && e.contains("1.001e3") && e.contains("raise the spacing"), "{e}");
        let machine = CellBudget::machine();
        if let Some(total) = crate::limits::memory_total() {
            let e = machine.check("x", 2.0 * total as f64 / SIMULATION_BYTES_PER_CELL, "k").unwrap_err();
            assert!(e.to_string().contains("GB to simulate"), "{e}");
        }
    }
}
