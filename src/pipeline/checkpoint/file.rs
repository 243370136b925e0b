//! The checkpoint of a load path (`output.checkpoint`, `solve --checkpoint`): after each
//! completed step but the last, rank 0 writes what the next step needs to `x.checkpoint.h5`
//! beside result `x.h5` — the step, λ (the walk's warm start y) and the tangential jump B_T u,
//! σ_max kept, the scene's ε, the steps' records for `/steps` and the guard's tightenings — and
//! the digests of what the run depends on (scene text after `--set`, mesh files' bytes,
//! program version). [`read`] loads it back for `solve --resume`, refusing a truncated, corrupt
//! or foreign one with one line naming what differs.
//!
//! **Global numbering.** TFETI spreads λ over the ranks (each its owned rows); the owned rows'
//! global ids (`Space::global_index`) come from the decomposition alone, not from the rank
//! count (`feti::distribution`). So rank 0 gathers (global id, value) pairs and stores y and
//! the jump as whole global vectors; a resume on any rank count takes its owned rows back by
//! global id. The steps' records keep their nodes' and cells' global numbers; on resume rank 0
//! writes every earlier step's rows (each row once over the ranks, as the writer wants).
//!
//! **Atomic.** The file is written under a temporary name (tracked by [`super::tmpfiles`]),
//! fsynced, the previous checkpoint renamed to `x.checkpoint.prev.h5`, then the new one renamed
//! into place, under [`tmpfiles::hold`] so a signal never interleaves with the renames.
//! A payload digest (FNV-1a over every stored value) catches a corrupt file.

use std::path::{Path, PathBuf};

use crate::contact::state::ContactState;
use crate::error::{Error, Result};
use crate::output::tmpfiles;
use crate::pipeline::accuracy::Tightening;
use crate::pipeline::path::{StepOutput, StepReport};
use crate::pipeline::LocalFields;
use crate::scene::LoadedScene;

/// The checkpoint file of result file `h5`: `x.checkpoint.h5` for `x.h5`.
pub fn path_for(h5: &Path) -> PathBuf {
    h5.with_extension("checkpoint.h5")
}

/// The previous checkpoint kept beside it: `x.checkpoint.prev.h5`.
pub fn prev_for(h5: &Path) -> PathBuf {
    h5.with_extension("checkpoint.prev.h5")
}

/// 64-bit FNV-1a, fed piece by piece.
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Feeds `bytes`.
    pub fn feed(&mut self, bytes: &[u8]) -> &mut Self {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
        self
    }

    /// The digest so far.
    pub fn value(&self) -> u64 {
        self.0
    }
}

/// What a checkpoint depends on, each as a 64-bit FNV-1a digest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Digest {
    /// The scene after `--set` (its TOML as the result file stores it, `output.checkpoint` and
    /// `output.path` left out: they do not change the solution).
    pub scene: u64,
    /// The mesh files' bytes (every `file` key of the scene, in order).
    pub mesh: u64,
    /// The program version and its dependencies' versions.
    pub version: u64,
}

impl Digest {
    /// The digests of the run of `ls`.
    pub fn of(ls: &LoadedScene) -> Result<Self> {
        let mut scene = ls.scene.clone();
        scene.output.checkpoint = false;
        scene.output.path = None;
        let text = scene.to_toml();
        let mut files = Vec::new();
        if let Ok(v) = toml::from_str::<toml::Value>(&text) {
            mesh_files(&v, &mut files);
        }
        let mut mesh = Fnv::default();
        for f in files {
            let p = ls.dir().join(f);
            let bytes = std::fs::read(&p).map_err(|e| Error::io(p.display().to_string(), e))?;
            mesh.feed(&bytes);
        }
        let version = crate::versions().to_string();
        Ok(Digest { scene: Fnv::default().feed(text.as_bytes()).value(), mesh: mesh.value(), version: Fnv::default().feed(version.as_bytes()).value() })
    }

    /// What differs from `other` (`None`: nothing).
    pub fn differs(&self, other: &Digest) -> Option<&'static str> {
        if self.version != other.version {
            Some("the program version")
        } else if self.scene != other.scene {
            Some("the scene (after --set)")
        } else if self.mesh != other.mesh {
            Some("the mesh files")
        } else {
            None
        }
    }
}

/// Every string under a key `file` of the scene's TOML (the mesh files), in order.
fn mesh_files(v: &toml::Value, out: &mut Vec<String>) {
    match v {
        toml::Value::Table(t) => {
            for (k, x) in t {
                match (k.as_str(), x) {
                    ("file", toml::Value::String(s)) => out.push(s.clone()),
                    _ => mesh_files(x, out),
                }
            }
        }
        toml::Value::Array(a) => a.iter().for_each(|x| mesh_files(x, out)),
        _ => {}
    }
}

/// One completed step's record with its rows in global numbering (all ranks' rows on rank 0).
#[derive(Clone, Debug, Default)]
pub struct Record {
    /// The step's figures.
    pub report: StepReport,
    /// u and von Mises on their nodes and cells (global numbers).
    pub local: LocalFields,
    /// The contact state (whole).
    pub state: ContactState,
}

impl Record {
    /// The record as the walk keeps it: the rows on rank 0 (`root`), none elsewhere.
    pub fn to_step(&self, root: bool) -> StepOutput {
        StepOutput { report: self.report.clone(), local: if root { self.local.clone() } else { LocalFields::default() }, state: self.state.clone() }
    }
}

/// What the step after `step` needs.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// The last completed step.
    pub step: usize,
    /// The path's steps.
    pub steps: usize,
    /// λ of the last step (the warm start y), global rows.
    pub y: Vec<f64>,
    /// The tangential jump B_T u of the last step, global rows.
    pub jump: Vec<f64>,
    /// σ_max kept for the next solve (`None`: measure again).
    pub sigma: Option<f64>,
    /// ε the walk starts each step from (the scene's).
    pub eps: f64,
    /// Every completed step's record.
    pub records: Vec<Record>,
    /// Where the accuracy guard tightened ε so far.
    pub tightenings: Vec<Tightening>,
    /// What the run depends on.
    pub digest: Digest,
    /// The file it was read from (empty when written).
    pub path: PathBuf,
}

/// Meta data stored as JSON bytes (integers and the tightenings; every f64 of the solution is
/// stored in a dataset, bit for bit).
#[derive(serde::Serialize, serde::Deserialize)]
struct Meta {
    step: usize,
    steps: usize,
    sigma_bits: Option<u64>,
    eps_bits: u64,
    records: usize,
    on_slip_bound: Vec<usize>,
    tightenings: Vec<Tightening>,
    scene: String,
    mesh: String,
    version: String,
    payload: String,
}

const REPORT_F: usize = 8;
const REPORT_N: usize = 9;

fn report_f(r: &StepReport) -> [f64; REPORT_F] {
    let f = r.total_force_on_slave;
    [r.final_relative_reduced_gradient, r.kkt_worst, f[0], f[1], f[2], r.max_displacement, r.time_s, 0.0]
}

fn report_n(r: &StepReport) -> [u64; REPORT_N] {
    [r.step, r.outer_iterations, r.n_a, r.inner_iterations, r.fixed_point_iterations, r.open, r.contact, r.stick, r.slip].map(|x| x as u64)
}

fn report_from(f: &[f64], n: &[u64]) -> StepReport {
    let n: Vec<usize> = n.iter().map(|&x| x as usize).collect();
    StepReport {
        step: n[0],
        outer_iterations: n[1],
        n_a: n[2],
        inner_iterations: n[3],
        fixed_point_iterations: n[4],
        final_relative_reduced_gradient: f[0],
        kkt_worst: f[1],
        open: n[5],
        contact: n[6],
        stick: n[7],
        slip: n[8],
        total_force_on_slave: [f[2], f[3], f[4]],
        max_displacement: f[5],
        time_s: f[6],
    }
}

/// The datasets of a checkpoint: (name, f64 values) and (name, u64 values).
type Arrays = (Vec<(String, Vec<f64>)>, Vec<(String, Vec<u64>)>);

fn arrays(c: &Checkpoint) -> Arrays {
    let mut f = vec![("y".to_string(), c.y.clone()), ("jump".to_string(), c.jump.clone())];
    let mut n = Vec::new();
    for (j, r) in c.records.iter().enumerate() {
        let s = &r.state;
        f.push((format!("r{j}_report"), report_f(&r.report).to_vec()));
        n.push((format!("r{j}_counts"), report_n(&r.report).to_vec()));
        n.push((format!("r{j}_nodes"), r.local.nodes.iter().map(|&x| x as u64).collect()));
        f.push((format!("r{j}_u"), r.local.displacement.iter().flatten().copied().collect()));
        n.push((format!("r{j}_cells"), r.local.cells.iter().map(|&x| x as u64).collect()));
        f.push((format!("r{j}_von_mises"), r.local.von_mises.clone()));
        n.push((format!("r{j}_status"), s.status.iter().map(|&x| x as i64 as u64).collect()));
        f.push((format!("r{j}_normal_force"), s.normal_force.clone()));
        f.push((format!("r{j}_tangential_force"), s.tangential_force.iter().flatten().copied().collect()));
        f.push((format!("r{j}_gap"), s.gap.clone()));
        f.push((format!("r{j}_slip"), s.slip.iter().flatten().copied().collect()));
    }
    (f, n)
}

fn payload_digest(a: &Arrays) -> u64 {
    let mut h = Fnv::default();
    for (name, v) in &a.0 {
        h.feed(name.as_bytes());
        v.iter().for_each(|x| {
            h.feed(&x.to_le_bytes());
        });
    }
    for (name, v) in &a.1 {
        h.feed(name.as_bytes());
        v.iter().for_each(|x| {
            h.feed(&x.to_le_bytes());
        });
    }
    h.value()
}

/// Writes `c` to `path` atomically (temporary name, fsync, the old one kept as `prev`).
pub fn write(path: &Path, prev: &Path, c: &Checkpoint) -> Result<()> {
    let shown = path.display().to_string();
    let a = arrays(c);
    let meta = Meta {
        step: c.step,
        steps: c.steps,
        sigma_bits: c.sigma.map(f64::to_bits),
        eps_bits: c.eps.to_bits(),
        records: c.records.len(),
        on_slip_bound: c.records.iter().map(|r| r.state.on_slip_bound).collect(),
        tightenings: c.tightenings.clone(),
        scene: format!("{:016x}", c.digest.scene),
        mesh: format!("{:016x}", c.digest.mesh),
        version: format!("{:016x}", c.digest.version),
        payload: format!("{:016x}", payload_digest(&a)),
    };
    let meta = serde_json::to_vec(&meta).map_err(|e| Error::output(&shown, format!("checkpoint: {e}")))?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display().to_string(), e))?;
    }
    let tmp = crate::output::staging(path, &tmpfiles::token());
    tmpfiles::track(&tmp);
    let result = (|| -> std::result::Result<(), ::hdf5::Error> {
        let file = ::hdf5::File::create(&tmp)?;
        file.new_dataset::<u8>().shape(meta.len()).create("meta")?.write_raw(&meta)?;
        for (name, v) in &a.0 {
            file.new_dataset::<f64>().shape(v.len()).create(name.as_str())?.write_raw(v)?;
        }
        for (name, v) in &a.1 {
            file.new_dataset::<u64>().shape(v.len()).create(name.as_str())?.write_raw(v)?;
        }
        file.close()
    })()
    .map_err(|e| Error::output(&shown, format!("checkpoint: {e}")))
    .and_then(|()| std::fs::File::open(&tmp).and_then(|f| f.sync_all()).map_err(|e| Error::io(&shown, e)))
    .and_then(|()| {
        let _held = tmpfiles::hold();
        if path.exists() {
            std::fs::rename(path, prev).map_err(|e| Error::io(prev.display().to_string(), e))?;
        }
        std::fs::rename(&tmp, path).map_err(|e| Error::io(&shown, e))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    tmpfiles::untrack(&tmp);
    result
}

/// Reads checkpoint `path` and checks it against the run's `digest`: one line naming the file
/// and what is wrong (unreadable, corrupt, or what differs) otherwise.
pub fn read(path: &Path, digest: &Digest) -> Result<Checkpoint> {
    let shown = path.display().to_string();
    let bad = |msg: String| Error::output(&shown, format!("cannot resume from this checkpoint: {msg}"));
    let file = ::hdf5::File::open(path).map_err(|e| bad(format!("not a readable checkpoint (truncated or corrupt?): {}", first_line(&e.to_string()))))?;
    let f64s = |name: &str| -> Result<Vec<f64>> {
        file.dataset(name).and_then(|d| d.read_raw::<f64>()).map_err(|e| bad(format!("dataset {name}: {}", first_line(&e.to_string()))))
    };
    let u64s = |name: &str| -> Result<Vec<u64>> {
        file.dataset(name).and_then(|d| d.read_raw::<u64>()).map_err(|e| bad(format!("dataset {name}: {}", first_line(&e.to_string()))))
    };
    let meta = file.dataset("meta").and_then(|d| d.read_raw::<u8>()).map_err(|e| bad(format!("dataset meta: {}", first_line(&e.to_string()))))?;
    let meta: Meta = serde_json::from_slice(&meta).map_err(|e| bad(format!("meta: {e}")))?;
    let hex = |s: &str| u64::from_str_radix(s, 16).map_err(|_| bad(format!("meta: digest \"{s}\" is not hex")));
    let stored = Digest { scene: hex(&meta.scene)?, mesh: hex(&meta.mesh)?, version: hex(&meta.version)? };
    if let Some(what) = digest.differs(&stored) {
        return Err(bad(format!("{what} differs from the run that wrote it")));
    }
    let tri = |v: Vec<f64>| -> Vec<[f64; 3]> { v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect() };
    let mut records = Vec::with_capacity(meta.records);
    for j in 0..meta.records {
        let (rf, rn) = (f64s(&format!("r{j}_report"))?, u64s(&format!("r{j}_counts"))?);
        if rf.len() != REPORT_F || rn.len() != REPORT_N {
            return Err(bad(format!("record {j} has the wrong shape")));
        }
        let local = LocalFields {
            nodes: u64s(&format!("r{j}_nodes"))?.into_iter().map(|x| x as usize).collect(),
            displacement: tri(f64s(&format!("r{j}_u"))?),
            cells: u64s(&format!("r{j}_cells"))?.into_iter().map(|x| x as usize).collect(),
            von_mises: f64s(&format!("r{j}_von_mises"))?,
        };
        let state = ContactState {
            status: u64s(&format!("r{j}_status"))?.into_iter().map(|x| x as i64 as i32).collect(),
            normal_force: f64s(&format!("r{j}_normal_force"))?,
            tangential_force: tri(f64s(&format!("r{j}_tangential_force"))?),
            gap: f64s(&format!("r{j}_gap"))?,
            slip: tri(f64s(&format!("r{j}_slip"))?),
            on_slip_bound: meta.on_slip_bound.get(j).copied().unwrap_or(0),
        };
        records.push(Record { report: report_from(&rf, &rn), local, state });
    }
    let c = Checkpoint {
        step: meta.step,
        steps: meta.steps,
        y: f64s("y")?,
        jump: f64s("jump")?,
        sigma: meta.sigma_bits.map(f64::from_bits),
        eps: f64::from_bits(meta.eps_bits),
        records,
        tightenings: meta.tightenings,
        digest: stored,
        path: path.to_path_buf(),
    };
    if format!("{:016x}", payload_digest(&arrays(&c))) != meta.payload {
        return Err(bad("its values do not match their digest (corrupt)".into()));
    }
    if c.step == 0 || c.step >= c.steps {
        return Err(bad(format!("step {} of {} leaves nothing to resume", c.step, c.steps)));
    }
    Ok(c)
}

fn first_line(s: &str) -> String {
    s.lines().next().unwrap_or("").to_string()
}
