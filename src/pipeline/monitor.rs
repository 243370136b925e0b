//! The live monitor (PETSc's `-ksp_monitor`, deal.II's `pcout`): rank 0 prints each phase as it
//! starts and, through the solvers' [`qp::Monitor`], one line per outer iteration while the
//! solve runs. Off with `--quiet` and on the other ranks.

use std::io::Write;
use std::time::Instant;

use crate::qp;

/// Prints progress on rank 0 when `on`.
#[derive(Clone, Copy, Debug)]
pub struct Live {
    pub on: bool,
    pub start: Instant,
}

impl Default for Live {
    fn default() -> Self {
        Live { on: false, start: Instant::now() }
    }
}

impl Live {
    pub fn new(on: bool) -> Self {
        Live { on, start: Instant::now() }
    }

    /// `[   1.23 s] text`: a summary line (a load step's).
    pub fn line(&self, text: &str) {
        self.phase(text);
    }

    /// `[   1.23 s] name` as a phase starts.
    pub fn phase(&self, name: &str) {
        if self.on {
            println!("[{:>8.2} s] {name}", self.start.elapsed().as_secs_f64());
            let _ = std::io::stdout().flush();
        }
    }
}

impl qp::Monitor for Live {
    fn step(&mut self, k: usize, s: &qp::Step) {
        if !self.on {
            return;
        }
        if k == 0 {
            println!("{:>14} {:>6} {:>11} {:>7} {:>6} {:>7} {:>7} {:>6} {:>9}", "", "outer", "‖r̃‖/‖b‖", "nA", "inner", "active", "stick", "slip", "time [s]");
        }
        println!(
            "{:>14} {:>6} {:>11.3e} {:>7} {:>6} {:>7} {:>7} {:>6} {:>9.2}",
            "",
            k + 1,
            s.err,
            s.n_a,
            s.inner,
            s.normal_active,
            s.stick,
            s.slip,
            self.start.elapsed().as_secs_f64()
        );
        let _ = std::io::stdout().flush();
    }
}
