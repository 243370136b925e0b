//! The live monitor (PETSc's `-ksp_monitor`, deal.II's `pcout`): rank 0 prints each phase as it
//! starts and, through the solvers' [`qp::Monitor`], one line per outer iteration while the
//! solve runs, and a phase's [`Progress`] (the mesh read by bytes, the factorization by
//! subdomains, any phase by its time) once it has run 2 s: a bar on a terminal, plain lines on
//! stderr otherwise (at most one per [`PERIOD_VAR`] seconds). Off with `--quiet` and on the
//! other ranks, which pay nothing for it.

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::Arc;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::qp;

/// Prints progress on rank 0 when `on`.
#[derive(Clone, Copy, Debug)]
pub struct Live {
    /// Whether this rank prints (rank 0 without `--quiet`).
    pub on: bool,
    /// When the run started.
    pub start: Instant,
}

impl Default for Live {
    fn default() -> Self {
        Live { on: false, start: Instant::now() }
    }
}

impl Live {
    /// The monitor of a run started now, printing when `on`.
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

/// The environment variable that sets the period of the plain progress lines (seconds; default
/// 5). A phase shows progress from the moment it has run 2 s (or one period, when shorter).
pub const PERIOD_VAR: &str = "TRESCA_FETI_PROGRESS_PERIOD";

/// What a phase's progress counts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Unit {
    /// Time only: the phase reports no count.
    Time,
    /// Bytes of a file, shown in MB.
    Bytes,
    /// Items (subdomains, candidates), named.
    Items(&'static str),
}

/// The counters a phase bumps (atomics: the work never waits on the printer).
#[derive(Debug)]
struct Shared {
    done: AtomicU64,
    total: AtomicU64,
    stop: AtomicBool,
}

/// The progress of one phase on rank 0: a thread shows it — an `indicatif` bar on stderr when
/// stderr is a terminal, otherwise a plain line on stderr at most once per period — from the
/// moment the phase has run 2 s. Inert (no thread, no printing) when the monitor is off: on
/// ranks other than 0 and with `--quiet`. Dropped at the end of the phase.
#[derive(Debug, Default)]
pub struct Progress {
    shared: Option<Arc<Shared>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Progress {
    /// Progress of phase `label`, counted in `unit`, shown when `live` is on.
    pub fn start(live: &Live, label: &str, unit: Unit) -> Self {
        if !live.on {
            return Progress::default();
        }
        let shared = Arc::new(Shared { done: AtomicU64::new(0), total: AtomicU64::new(0), stop: AtomicBool::new(false) });
        let (s, label) = (shared.clone(), label.to_string());
        let period = period();
        let terminal = std::io::stderr().is_terminal();
        let thread = std::thread::Builder::new().name("progress".into()).spawn(move || show(&s, &label, unit, period, terminal)).ok();
        Progress { shared: Some(shared), thread }
    }

    /// `done` of `total` (in the phase's unit).
    pub fn set(&self, done: u64, total: u64) {
        if let Some(s) = &self.shared {
            s.done.store(done, Relaxed);
            s.total.store(total, Relaxed);
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let (Some(s), Some(t)) = (&self.shared, self.thread.take()) {
            s.stop.store(true, Relaxed);
            t.thread().unpark();
            let _ = t.join();
        }
    }
}

/// The period of the plain lines: [`PERIOD_VAR`], 5 s when unset or not a positive number.
fn period() -> Duration {
    let secs = std::env::var(PERIOD_VAR).ok().and_then(|v| v.trim().parse::<f64>().ok()).filter(|s| s.is_finite() && *s > 0.0).unwrap_or(5.0);
    Duration::from_secs_f64(secs)
}

/// `41 % (27 of 65 MB)`, `3 of 8 subdomains`, or nothing (no count yet or a time-only phase).
fn count(unit: Unit, done: u64, total: u64) -> String {
    match unit {
        _ if total == 0 => String::new(),
        Unit::Time => String::new(),
        Unit::Bytes => format!("{:.0} % ({:.0} of {:.0} MB), ", 100.0 * done as f64 / total as f64, done as f64 / 1e6, total as f64 / 1e6),
        Unit::Items(what) => format!("{done} of {total} {what}, "),
    }
}

/// The printer thread: waits 2 s (or one period), then shows the counters until the phase ends.
fn show(s: &Shared, label: &str, unit: Unit, period: Duration, terminal: bool) {
    let start = Instant::now();
    let first = period.min(Duration::from_secs(2));
    let wait = |until: Instant| {
        while !s.stop.load(Relaxed) {
            let now = Instant::now();
            if now >= until {
                return true;
            }
            std::thread::park_timeout(until - now);
        }
        false
    };
    if !wait(start + first) {
        return;
    }
    if terminal {
        let bar = match unit {
            Unit::Time => ProgressBar::new_spinner(),
            _ => ProgressBar::new(s.total.load(Relaxed).max(1)),
        };
        let style = match unit {
            Unit::Time => ProgressStyle::with_template("{spinner} {msg} {elapsed}"),
            Unit::Bytes => ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3} % ({bytes} of {total_bytes}), {elapsed}"),
            Unit::Items(_) => ProgressStyle::with_template("{msg} [{bar:40}] {pos} of {len}, {elapsed}"),
        };
        bar.set_draw_target(ProgressDrawTarget::stderr());
        if let Ok(style) = style {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(label.to_string());
        bar.enable_steady_tick(Duration::from_millis(200));
        let tick = Duration::from_millis(200);
        loop {
            bar.set_length(s.total.load(Relaxed).max(1));
            bar.set_position(s.done.load(Relaxed));
            if !wait(Instant::now() + tick) {
                break;
            }
        }
        bar.finish_and_clear();
        return;
    }
    loop {
        let text = count(unit, s.done.load(Relaxed), s.total.load(Relaxed));
        let line = format!("{label}: {text}{:.2} s\n", start.elapsed().as_secs_f64());
        let _ = std::io::stderr().lock().write_all(line.as_bytes());
        if !wait(Instant::now() + period) {
            break;
        }
    }
}
