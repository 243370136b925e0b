//! Writing the load path's checkpoints from the walk ([`Saver`]): after each completed step
//! but the last, every rank sends rank 0 its dual rows (y and the jump, by global id) and its
//! rows of the new step's record; rank 0 writes the file ([`file`]) and
//! tells the signal thread which step the checkpoint holds, for its one line. [`read`] loads
//! and checks one for `solve --resume` before the solve starts.

use std::path::PathBuf;

use super::path::Walk;
use super::LocalFields;
use crate::comm::Comm;
use crate::error::Result;
pub(crate) mod file;

use crate::output::tmpfiles;
use crate::scene::LoadedScene;
pub(crate) use file::Checkpoint;
use file::{Digest, Record};

/// The checkpoints of one walk (`output.checkpoint`; inactive otherwise).
pub(crate) struct Saver<'a, C: Comm> {
    comm: &'a C,
    /// The files (current, previous) and the run's digest, when checkpoints are written.
    target: Option<(PathBuf, PathBuf, Digest)>,
    /// Every completed step's record with all ranks' rows (rank 0; empty elsewhere).
    records: Vec<Record>,
    scene: PathBuf,
}

impl<'a, C: Comm> Saver<'a, C> {
    /// The saver of a walk of `ls` (`on_path`: more than one step; one step writes none).
    pub fn new(comm: &'a C, ls: &LoadedScene, on_path: bool) -> Result<Self> {
        let target = if ls.scene.output.checkpoint && on_path {
            let digest = comm.agree(Digest::of(ls))?;
            let h5 = ls.output_path();
            Some((file::path_for(&h5), file::prev_for(&h5), digest))
        } else {
            None
        };
        Ok(Saver { comm, target, records: vec![], scene: ls.path.clone() })
    }

    /// Whether checkpoints are written (a phase of their own then).
    pub fn active(&self) -> bool {
        self.target.is_some()
    }

    /// Continues after checkpoint `c`: its records are the first ones.
    pub fn resumed(&mut self, c: &Checkpoint) {
        if self.comm.is_root() {
            self.records = c.records.clone();
        }
    }

    /// Step `k` of the walk completed (not the last): writes its checkpoint (collective).
    pub fn save(&mut self, walk: &Walk, k: usize, rows: &[usize]) -> Result<()> {
        let Some((path, prev, digest)) = &self.target else { return Ok(()) };
        let comm = self.comm;
        let y = gather_by_id(comm, rows, &walk.y);
        let jump = gather_by_id(comm, rows, &walk.jump);
        if let Some(last) = walk.records().last() {
            let local = gather_local(comm, &last.local);
            self.records.push(Record { report: last.report.clone(), local, state: last.state.clone() });
        }
        if !comm.is_root() {
            return Ok(());
        }
        let c = Checkpoint {
            step: k,
            steps: walk.steps,
            y,
            jump,
            sigma: walk.params.common.sigma,
            eps: walk.params.common.eps,
            records: self.records.clone(),
            tightenings: walk.tightenings().to_vec(),
            digest: *digest,
            path: PathBuf::new(),
        };
        file::write(path, prev, &c)?;
        tmpfiles::note_checkpoint(k, walk.steps, &self.scene, path);
        stop_for_tests(k);
        Ok(())
    }
}

/// The checkpoint `path` for a run of `ls`, checked against its scene, meshes and program
/// (collective: every rank reads it).
pub(crate) fn read<C: Comm>(comm: &C, ls: &LoadedScene, path: &std::path::Path) -> Result<Checkpoint> {
    comm.agree(Digest::of(ls).and_then(|d| file::read(path, &d)))
}

/// A distributed vector whole on rank 0 by the global ids of its entries (`rows`; replicated
/// entries arrive once per rank with equal values). Empty on the other ranks.
fn gather_by_id<C: Comm>(comm: &C, rows: &[usize], x: &[f64]) -> Vec<f64> {
    let ids: Vec<f64> = rows.iter().map(|&r| r as f64).collect();
    let (Some(ids), Some(vals)) = (comm.gather_f64(0, &ids), comm.gather_f64(0, x)) else { return vec![] };
    let n = ids.iter().flatten().map(|&r| r as usize + 1).max().unwrap_or(0);
    let mut g = vec![0.0; n];
    for (i, v) in ids.iter().zip(&vals) {
        for (&r, &x) in i.iter().zip(v) {
            g[r as usize] = x;
        }
    }
    g
}

/// Every rank's rows of a step's fields on rank 0 (in rank order; empty elsewhere).
fn gather_local<C: Comm>(comm: &C, l: &LocalFields) -> LocalFields {
    let as_f = |v: &[usize]| v.iter().map(|&x| x as f64).collect::<Vec<f64>>();
    let u: Vec<f64> = l.displacement.iter().flatten().copied().collect();
    let parts = [comm.gather_f64(0, &as_f(&l.nodes)), comm.gather_f64(0, &u), comm.gather_f64(0, &as_f(&l.cells)), comm.gather_f64(0, &l.von_mises)];
    let [Some(nodes), Some(u), Some(cells), Some(vm)] = parts else { return LocalFields::default() };
    let ids = |p: Vec<Vec<f64>>| p.into_iter().flatten().map(|x| x as usize).collect();
    LocalFields {
        nodes: ids(nodes),
        displacement: u.into_iter().flatten().collect::<Vec<f64>>().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        cells: ids(cells),
        von_mises: vm.into_iter().flatten().collect(),
    }
}

/// `TRESCA_FETI_STOP_AFTER=<k>`: rank 0 sends itself SIGTERM once the checkpoint of step k is
/// written, as Slurm would (to test the stop and the resume).
fn stop_for_tests(k: usize) {
    if std::env::var("TRESCA_FETI_STOP_AFTER").ok().and_then(|v| v.parse::<usize>().ok()) == Some(k) {
        // SAFETY: raise only delivers a signal to this process; the signal thread ends it.
        unsafe { libc::raise(libc::SIGTERM) };
        std::thread::sleep(std::time::Duration::from_secs(60));
    }
}
