//! The solved problem in the FCLIB *global* format (github.com/FrictionalContactLibrary/fclib,
//! `src/fclib.h`), for other frictional-contact solvers (Siconos reads it with
//! `globalFrictionContact_fclib_read`). FCLIB's global problem is
//!
//! ```text
//! M v = H r + f,   u = Hᵀv + w,   ũ = u + [μ‖u_T‖, 0, 0] per contact,   K*_μ ∋ ũ ⊥ r ∈ K_μ
//! ```
//!
//! with, per contact, the columns of H and the entries of u, r, w ordered (normal, t₁, t₂) and
//! the cone K_μ = {‖r_T‖ ≤ μ r_N}. Ours (the monolithic dual, quasi-static, displacements) is
//! K u = f − Bᵀλ per body with B_N u ≤ c_N, λ_N ≥ 0, ‖λ_T‖ ≤ μλ_N and λ_T opposite to the
//! tangential part of c − B u, so the map is
//!
//! ```text
//! v = u,   M = K (block diagonal over the bodies' free DOFs, bodies in order),   f = f,
//! H = −Bᵀ,   r = λ,   w = c,   hence u_fclib = c − B u (the gap on the normal rows).
//! ```
//!
//! Layout written (as `fclib_write_global` and `fclib_write_guesses` do; integers are 32-bit,
//! every "scalar" a 1-element dataset, strings scalar fixed-length and NUL-terminated):
//!
//! | path | type | shape |
//! |---|---|---|
//! | `/fclib_global/spacedim` | i32 | 1 (= 3) |
//! | `/fclib_global/{M,H}/{nzmax,m,n,nz}` | i32 | 1 each |
//! | `/fclib_global/{M,H}/{i,p}` | i32 | nz |
//! | `/fclib_global/{M,H}/x` | f64 | nz |
//! | `/fclib_global/vectors/{f,w,mu}` | f64 | n, 3n_c, n_c |
//! | `/fclib_global/info/{title,description,math_info}` | string | scalar |
//! | `/guesses/number_of_guesses` | i32 | 1 (= 1) |
//! | `/guesses/1/{v,u,r}` | f64 | n, 3n_c, 3n_c |
//!
//! Both matrices are triplets (nz = nzmax = number of entries, no duplicates, sorted by column
//! then row) with CSparse's meaning, the one Siconos writes and reads: `i` the row indices, `p`
//! the column indices. (The comment in `fclib.h` names them the other way round; Siconos'
//! reader mishandles compressed columns, so triplets are the portable choice.) M is stored
//! whole, both triangles.

use std::path::{Path, PathBuf};

use super::monolithic::{BodyBlock, MonolithicDual};
use super::DualProblem;
use crate::comm::Comm;
use crate::contact::pairing::Contact;
use crate::error::{Error, Result};
use crate::qp::cone::Coefficient;

/// The scene key named by the errors.
const KEY: &str = "output.export_fclib";

/// A sparse matrix as triplets (row, column, value).
#[derive(Clone, Debug, Default, PartialEq)]
struct Triplets {
    m: usize,
    n: usize,
    rows: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
}

impl Triplets {
    /// From entries that may repeat (summed), sorted by column then row.
    fn from_entries(m: usize, n: usize, entries: impl IntoIterator<Item = (usize, usize, f64)>) -> Self {
        let mut map = std::collections::BTreeMap::new();
        for (i, j, v) in entries {
            *map.entry((j, i)).or_insert(0.0) += v;
        }
        let mut t = Triplets { m, n, ..Default::default() };
        for ((j, i), v) in map {
            t.rows.push(i);
            t.cols.push(j);
            t.vals.push(v);
        }
        t
    }
}

/// The global problem and the guess, assembled on rank 0.
#[derive(Clone, Debug, PartialEq)]
struct Global {
    m: Triplets,
    h: Triplets,
    f: Vec<f64>,
    w: Vec<f64>,
    mu: Vec<f64>,
    v: Vec<f64>,
    u: Vec<f64>,
    r: Vec<f64>,
}

/// One body's part as gathered on rank 0 (free-DOF numbering of the body).
struct BodyPart {
    body: usize,
    nfree: usize,
    /// Lower triangle of K: (row, column, value).
    k: Vec<(usize, usize, f64)>,
    f: Vec<f64>,
    u: Vec<f64>,
    /// B entries: (row of B, free DOF, coefficient).
    b: Vec<(usize, usize, f64)>,
}

/// Bodies as one f64 buffer (a rank's part): count, then per body its index, free DOFs, entries
/// of K's lower triangle, B entries, then K (row, column, value)…, f, u, B (row, DOF, coef)….
fn pack<'a>(blocks: impl ExactSizeIterator<Item = (&'a BodyBlock, &'a [f64])>) -> Vec<f64> {
    let mut buf = vec![blocks.len() as f64];
    for (blk, ub) in blocks {
        let k = &blk.local.sys.k;
        buf.extend([blk.local.body as f64, k.n as f64, k.nnz() as f64, blk.b.len() as f64]);
        for j in 0..k.n {
            for p in k.col_ptr[j]..k.col_ptr[j + 1] {
                buf.extend([k.row_idx[p] as f64, j as f64, k.values[p]]);
            }
        }
        buf.extend_from_slice(&blk.local.sys.f);
        buf.extend_from_slice(ub);
        for &(r, j, c) in &blk.b {
            buf.extend([r as f64, j as f64, c]);
        }
    }
    buf
}

/// The inverse of [`pack`] over every rank's buffer.
fn unpack(bufs: &[Vec<f64>]) -> Vec<BodyPart> {
    let mut parts = Vec::new();
    for buf in bufs {
        let mut it = buf.iter().copied();
        let mut next = || it.next().expect("a packed body buffer");
        let count = next() as usize;
        for _ in 0..count {
            let (body, nfree, nnz, nb) = (next() as usize, next() as usize, next() as usize, next() as usize);
            let k = (0..nnz).map(|_| (next() as usize, next() as usize, next())).collect();
            let f = (0..nfree).map(|_| next()).collect();
            let u = (0..nfree).map(|_| next()).collect();
            let b = (0..nb).map(|_| (next() as usize, next() as usize, next())).collect();
            parts.push(BodyPart { body, nfree, k, f, u, b });
        }
    }
    parts.sort_by_key(|p| p.body);
    parts
}

/// FCLIB's position (contact, then normal, t₁, t₂) of every multiplier of our layout.
fn fclib_positions<C: Comm>(dual: &MonolithicDual<'_, C>) -> Vec<usize> {
    let layout = dual.layout;
    let mut pos = vec![0; layout.dim()];
    for i in 0..layout.m {
        pos[layout.normal(i)] = 3 * i;
        for k in 0..2 {
            pos[layout.tangent(i, k)] = 3 * i + 1 + k;
        }
    }
    pos
}

/// M, H, f, w, v, r and u = Hᵀv + w from the gathered bodies.
fn assemble(parts: &[BodyPart], pos: &[usize], c: &[f64], lambda: &[f64], mu: Vec<f64>) -> Global {
    let nc = mu.len();
    let mut offset = 0;
    let (mut m_entries, mut h_entries) = (Vec::new(), Vec::new());
    let (mut f, mut v) = (Vec::new(), Vec::new());
    for p in parts {
        for &(i, j, x) in &p.k {
            m_entries.push((offset + i, offset + j, x));
            if i != j {
                m_entries.push((offset + j, offset + i, x));
            }
        }
        for &(row, j, coef) in &p.b {
            h_entries.push((offset + j, pos[row], -coef));
        }
        f.extend_from_slice(&p.f);
        v.extend_from_slice(&p.u);
        offset += p.nfree;
    }
    let n = offset;
    let (m, h) = (Triplets::from_entries(n, n, m_entries), Triplets::from_entries(n, 3 * nc, h_entries));
    let (mut w, mut r) = (vec![0.0; 3 * nc], vec![0.0; 3 * nc]);
    for (row, &p) in pos.iter().enumerate() {
        w[p] = c[row];
        r[p] = lambda[row];
    }
    let mut u = w.clone();
    for ((&i, &j), &x) in h.rows.iter().zip(&h.cols).zip(&h.vals) {
        u[j] += x * v[i];
    }
    Global { m, h, f, w, mu, v, u, r }
}

/// Writes the solved problem in the FCLIB global format (rank 0 writes; every rank takes part).
///
/// `title` (the scene's) goes into `/fclib_global/info/description`; the info's title is
/// "tresca-feti". Every pair must follow isotropic Coulomb friction. The file is written under
/// `<path>.tmp` and renamed: a failure leaves no file. Collective: every rank returns the same
/// result.
pub fn write_global<C: Comm>(comm: &C, path: &std::path::Path, dual: &MonolithicDual<'_, C>, contact: &Contact, lambda: &[f64], title: &str) -> Result<()> {
    let mu: Vec<f64> = contact
        .coulomb
        .iter()
        .map(|c| match *c {
            Coefficient::Isotropic(mu) => Ok(mu),
            _ => Err(Error::scene(KEY, "exports isotropic Coulomb friction on every pair (friction = { type = \"coulomb\", mu })")),
        })
        .collect::<Result<_>>()?;
    if contact.is_empty() || !dual.layout.friction || dual.layout.m != contact.len() || dual.layout.free != 0 {
        return Err(Error::scene(KEY, "exports a contact problem with friction on the monolithic dual"));
    }
    if lambda.len() != dual.layout.dim() {
        return Err(Error::output(path.display().to_string(), format!("λ has {} entries, the dual {}", lambda.len(), dual.layout.dim())));
    }
    // v = u = K⁻¹(f − Bᵀλ) on every body (collective)
    let rec = dual.recover(lambda);
    let gathered = comm.gather_f64(0, &pack(dual.blocks.iter().zip(rec.u.iter().map(Vec::as_slice))));
    let written = match gathered {
        Some(bufs) => {
            let global = assemble(&unpack(&bufs), &fclib_positions(dual), dual.c(), lambda, mu);
            write_file(path, &global, title)
        }
        None => Ok(()),
    };
    comm.agree(written)
}

/// Rank 0: the file under a temporary name, renamed when complete.
fn write_file(path: &Path, g: &Global, title: &str) -> Result<()> {
    let shown = path.display().to_string();
    let fits = |x: usize| i32::try_from(x).is_ok();
    if ![g.m.n, g.h.n, g.m.vals.len(), g.h.vals.len()].into_iter().all(fits) {
        return Err(Error::output(shown, "too large for FCLIB's 32-bit indices"));
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display().to_string(), e))?;
    }
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    crate::output::tmpfiles::track(&tmp);
    let result = write_h5(&tmp, g, title).map_err(|msg| Error::output(&shown, msg)).and_then(|()| {
        let _held = crate::output::tmpfiles::hold();
        std::fs::rename(&tmp, path).map_err(|e| Error::io(&shown, e))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    crate::output::tmpfiles::untrack(&tmp);
    result
}

type R<T> = std::result::Result<T, String>;

fn h5e(what: &str) -> impl FnOnce(::hdf5::Error) -> String + '_ {
    move |e| format!("{what}: {e}")
}

fn write_h5(path: &Path, g: &Global, title: &str) -> R<()> {
    let file = ::hdf5::File::create(path).map_err(h5e("cannot create file"))?;
    // every group handle is gone before the file closes
    write_contents(&file, g, title)?;
    file.close().map_err(h5e("closing"))
}

fn write_contents(file: &::hdf5::File, g: &Global, title: &str) -> R<()> {
    let root = file.create_group("fclib_global").map_err(h5e("/fclib_global"))?;
    write_i32(&root, "spacedim", 3)?;
    for (name, mat) in [("M", &g.m), ("H", &g.h)] {
        let grp = root.create_group(name).map_err(h5e(name))?;
        write_matrix(&grp, mat)?;
    }
    let vectors = root.create_group("vectors").map_err(h5e("vectors"))?;
    write_f64(&vectors, "f", &g.f)?;
    write_f64(&vectors, "w", &g.w)?;
    write_f64(&vectors, "mu", &g.mu)?;
    let info = root.create_group("info").map_err(h5e("info"))?;
    write_string(&info, "title", "tresca-feti")?;
    let description = format!(
        "{title}: the frictional contact problem solved by tresca-feti (quasi-static linear elasticity, \
         displacements; v = u on the bodies' free DOFs, bodies in order). M = K block diagonal, f the loads, \
         H = -B^T, w = c (the gap on the normal rows), r = lambda; per contact (normal, t1, t2). \
         Guess 1 is tresca-feti's solution."
    );
    write_string(&info, "description", &description)?;
    write_string(&info, "math_info", "Coulomb, node-to-node, 3D")?;
    let guesses = file.create_group("guesses").map_err(h5e("/guesses"))?;
    write_i32(&guesses, "number_of_guesses", 1)?;
    let first = guesses.create_group("1").map_err(h5e("/guesses/1"))?;
    write_f64(&first, "v", &g.v)?;
    write_f64(&first, "u", &g.u)?;
    write_f64(&first, "r", &g.r)
}

/// FCLIB's `write_matrix` for a triplet matrix (nz = nzmax = entries).
fn write_matrix(grp: &::hdf5::Group, t: &Triplets) -> R<()> {
    let nz = t.vals.len() as i32;
    write_i32(grp, "nzmax", nz)?;
    write_i32(grp, "m", t.m as i32)?;
    write_i32(grp, "n", t.n as i32)?;
    write_i32(grp, "nz", nz)?;
    let ints = |v: &[usize]| v.iter().map(|&x| x as i32).collect::<Vec<i32>>();
    write_ints(grp, "p", &ints(&t.cols))?;
    write_ints(grp, "i", &ints(&t.rows))?;
    write_f64(grp, "x", &t.vals)
}

fn write_i32(grp: &::hdf5::Group, name: &str, v: i32) -> R<()> {
    write_ints(grp, name, &[v])
}

fn write_ints(grp: &::hdf5::Group, name: &str, v: &[i32]) -> R<()> {
    let what = format!("{}/{name}", grp.name());
    grp.new_dataset::<i32>().shape([v.len()]).create(name).and_then(|d| d.write_raw(v)).map_err(h5e(&what))
}

fn write_f64(grp: &::hdf5::Group, name: &str, v: &[f64]) -> R<()> {
    let what = format!("{}/{name}", grp.name());
    grp.new_dataset::<f64>().shape([v.len()]).create(name).and_then(|d| d.write_raw(v)).map_err(h5e(&what))
}

/// A scalar C string dataset as `H5LTmake_dataset_string` makes it: fixed length strlen + 1,
/// NUL-terminated, ASCII (UTF-8 when the text is not ASCII: the same bytes to a C reader).
fn write_string(grp: &::hdf5::Group, name: &str, value: &str) -> R<()> {
    use hdf5_sys::h5d::{H5Dclose, H5Dcreate2, H5Dwrite};
    use hdf5_sys::h5p::H5P_DEFAULT;
    use hdf5_sys::h5s::{H5S_class_t, H5Sclose, H5Screate, H5S_ALL};
    use hdf5_sys::h5t::{H5T_cset_t, H5T_str_t, H5Tclose, H5Tcopy, H5Tset_cset, H5Tset_size, H5Tset_strpad, H5T_C_S1};
    let what = format!("{}/{name}", grp.name());
    let cname = std::ffi::CString::new(name).map_err(|e| format!("{what}: {e}"))?;
    let bytes = std::ffi::CString::new(value).map_err(|e| format!("{what}: an interior NUL ({e})"))?;
    let bytes = bytes.as_bytes_with_nul();
    // SAFETY: plain HDF5 C calls on ids created and closed here and on the live group's id;
    // the buffer holds exactly the type's size (the string and its NUL). They run under
    // hdf5-metno's global lock like its own calls (HDF5 is not thread-safe).
    let ok = ::hdf5::sync::sync(|| unsafe {
        let tid = H5Tcopy(*H5T_C_S1);
        if tid < 0 {
            return false;
        }
        let sid = H5Screate(H5S_class_t::H5S_SCALAR);
        let cset = if value.is_ascii() { H5T_cset_t::H5T_CSET_ASCII } else { H5T_cset_t::H5T_CSET_UTF8 };
        let mut ok = sid >= 0 && H5Tset_size(tid, bytes.len()) >= 0 && H5Tset_strpad(tid, H5T_str_t::H5T_STR_NULLTERM) >= 0 && H5Tset_cset(tid, cset) >= 0;
        if ok {
            let did = H5Dcreate2(grp.id(), cname.as_ptr(), tid, sid, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
            ok = did >= 0 && H5Dwrite(did, tid, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.as_ptr().cast()) >= 0;
            if did >= 0 {
                ok &= H5Dclose(did) >= 0;
            }
        }
        if sid >= 0 {
            H5Sclose(sid);
        }
        H5Tclose(tid);
        ok
    });
    if ok {
        Ok(())
    } else {
        Err(format!("writing {what} failed"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comm::SerialComm;
    use crate::pipeline::{assemble_and_factorize, Timings};
    use crate::qp::{Operator, Qp, Silent};
    use crate::scene::{self, OrderingKind};

    fn tmp(name: &str) -> PathBuf {
        std::env::temp_dir().join(format!("tresca_feti_fclib_{}_{name}", std::process::id()))
    }

    /// The seed scene at N = 5 with `friction` and a prescribed displacement on the lower
    /// body's held face (it touches contact nodes: c gets tangential entries). With Coulomb
    /// μ = 0.3: 15 of the 25 pairs in contact, 8 sliding, 7 sticking.
    fn seed(friction: &str) -> (scene::LoadedScene, crate::model::Model, Vec<crate::dual::monolithic::LocalBody>) {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
        let sets = ["mesh.n=5".to_string(), "dirichlet.1.value=[1e-5, -2e-5, 3e-6]".to_string(), format!("contact.pair.0.friction={friction}")];
        let ls = scene::load(&path, &sets).unwrap();
        let model = crate::model::build(&ls).unwrap();
        let bodies = assemble_and_factorize(&SerialComm, &model, OrderingKind::Metis, true, &mut Timings::default()).unwrap();
        (ls, model, bodies)
    }

    fn read_f64(file: &::hdf5::File, name: &str) -> Vec<f64> {
        file.dataset(name).unwrap_or_else(|e| panic!("{name}: {e}")).read_raw::<f64>().unwrap()
    }

    fn read_i32(file: &::hdf5::File, name: &str) -> Vec<i32> {
        file.dataset(name).unwrap_or_else(|e| panic!("{name}: {e}")).read_raw::<i32>().unwrap()
    }

    /// A scalar fixed-length string dataset, read through its own type.
    fn read_string(file: &::hdf5::File, name: &str) -> String {
        use hdf5_sys::h5d::{H5Dget_type, H5Dread};
        use hdf5_sys::h5p::H5P_DEFAULT;
        use hdf5_sys::h5s::H5S_ALL;
        use hdf5_sys::h5t::{H5Tclose, H5Tget_size, H5Tis_variable_str};
        let ds = file.dataset(name).unwrap();
        assert!(ds.is_scalar(), "{name} is scalar");
        let bytes = ::hdf5::sync::sync(|| unsafe {
            let tid = H5Dget_type(ds.id());
            assert_eq!(H5Tis_variable_str(tid), 0, "{name}: fixed length");
            let mut buf = vec![0u8; H5Tget_size(tid)];
            assert!(H5Dread(ds.id(), tid, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.as_mut_ptr().cast()) >= 0);
            H5Tclose(tid);
            buf
        });
        assert_eq!(bytes.last(), Some(&0), "{name}: NUL-terminated");
        String::from_utf8(bytes[..bytes.len() - 1].to_vec()).unwrap()
    }

    /// y = A x (or Aᵀx) for a triplet matrix read from the file.
    fn matvec(file: &::hdf5::File, group: &str, x: &[f64], transpose: bool) -> Vec<f64> {
        let g = |k: &str| read_i32(file, &format!("{group}/{k}"));
        let (nzmax, m, n, nz) = (g("nzmax")[0] as usize, g("m")[0] as usize, g("n")[0] as usize, g("nz")[0]);
        assert!(nz >= 0 && nz as usize == nzmax, "{group}: a triplet matrix with nz = nzmax");
        let (rows, cols, vals) = (g("i"), g("p"), read_f64(file, &format!("{group}/x")));
        assert!(rows.len() == nzmax && cols.len() == nzmax && vals.len() == nzmax);
        assert!(rows.iter().all(|&i| (i as usize) < m) && cols.iter().all(|&j| (j as usize) < n));
        let mut y = vec![0.0; if transpose { n } else { m }];
        for ((&i, &j), &v) in rows.iter().zip(&cols).zip(&vals) {
            let (i, j) = (i as usize, j as usize);
            if transpose {
                y[j] += v * x[i];
            } else {
                y[i] += v * x[j];
            }
        }
        y
    }

    fn max_abs(v: &[f64]) -> f64 {
        v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
    }

    #[test]
    fn the_written_problem_holds_our_coulomb_solution() {
        let (ls, model, bodies) = seed("{type=\"coulomb\", mu=0.3}");
        let contact = model.pairs.as_ref().unwrap();
        let (dual, b) = MonolithicDual::new(&SerialComm, contact, bodies);
        let set = contact.constraint_set();
        let params = crate::pipeline::solver_for(&ls, &model).params.with_eps(1e-10);
        let sol = crate::qp::solve_friction(&Qp::new(&dual, &b, &set), Some(&contact.coulomb), &vec![0.0; dual.dim()], &params, &mut Silent).unwrap();
        let path = tmp("seed").join("fclib.h5");
        let _ = std::fs::remove_dir_all(path.parent().unwrap());
        write_global(&SerialComm, &path, &dual, contact, &sol.lambda, &ls.scene.title).unwrap();
        assert!(!tmp("seed").join("fclib.h5.tmp").exists());

        // everything below from the file's arrays alone
        let file = ::hdf5::File::open(&path).unwrap();
        assert_eq!(read_i32(&file, "fclib_global/spacedim"), [3]);
        let n = read_i32(&file, "fclib_global/M/n")[0] as usize;
        assert_eq!(read_i32(&file, "fclib_global/M/m")[0] as usize, n);
        assert_eq!(read_i32(&file, "fclib_global/H/m")[0] as usize, n);
        let nr = read_i32(&file, "fclib_global/H/n")[0] as usize;
        let nc = nr / 3;
        assert_eq!((nr, nc), (3 * contact.len(), 25));
        assert_eq!(n, dual.blocks.iter().map(|blk| blk.local.dofs.nfree).sum::<usize>());
        let (f, w, mu) = (read_f64(&file, "fclib_global/vectors/f"), read_f64(&file, "fclib_global/vectors/w"), read_f64(&file, "fclib_global/vectors/mu"));
        assert_eq!((f.len(), w.len()), (n, nr));
        assert_eq!(mu, vec![0.3; nc]);
        assert_eq!(read_string(&file, "fclib_global/info/title"), "tresca-feti");
        assert_eq!(read_string(&file, "fclib_global/info/math_info"), "Coulomb, node-to-node, 3D");
        assert!(read_string(&file, "fclib_global/info/description").starts_with(&ls.scene.title));
        assert_eq!(read_i32(&file, "guesses/number_of_guesses"), [1]);
        let (v, u, r) = (read_f64(&file, "guesses/1/v"), read_f64(&file, "guesses/1/u"), read_f64(&file, "guesses/1/r"));
        assert_eq!((v.len(), u.len(), r.len()), (n, nr, nr));
        // the prescribed shift reaches the tangential rows of w
        assert!((0..nc).any(|a| w[3 * a + 1] != 0.0 || w[3 * a + 2] != 0.0), "no tangential entry in w");

        // M is symmetric (stored whole)
        let mut seed = 3u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let x: Vec<f64> = (0..n).map(|_| rnd()).collect();
        let y: Vec<f64> = (0..n).map(|_| rnd()).collect();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>();
        let (xmy, ymx) = (dot(&x, &matvec(&file, "fclib_global/M", &y, false)), dot(&y, &matvec(&file, "fclib_global/M", &x, false)));
        assert!((xmy - ymx).abs() <= 1e-12 * xmy.abs().max(ymx.abs()), "{xmy} vs {ymx}");

        // M v = H r + f
        let mv = matvec(&file, "fclib_global/M", &v, false);
        let hr = matvec(&file, "fclib_global/H", &r, false);
        let res: Vec<f64> = (0..n).map(|k| mv[k] - hr[k] - f[k]).collect();
        let scale = max_abs(&mv).max(max_abs(&f));
        assert!(max_abs(&res) <= 1e-8 * scale, "‖Mv − Hr − f‖ = {:e} vs {scale:e}", max_abs(&res));
        // u = Hᵀv + w
        let htv = matvec(&file, "fclib_global/H", &v, true);
        let u2: Vec<f64> = (0..nr).map(|k| htv[k] + w[k]).collect();
        let (su, sr) = (max_abs(&u2), max_abs(&r));
        assert!(u.iter().zip(&u2).all(|(a, b)| (a - b).abs() <= 1e-12 * su), "stored u is not Hᵀv + w");

        // Coulomb: r ∈ K_μ, ũ = u + μ‖u_T‖e_N ∈ K*_μ, rᵀũ = 0, contact by contact
        let tol = 1e-7;
        let (mut touching, mut sliding, mut sticking) = (0, 0, 0);
        for a in 0..nc {
            let (un, ut) = (u2[3 * a], [u2[3 * a + 1], u2[3 * a + 2]]);
            let (rn, rt) = (r[3 * a], [r[3 * a + 1], r[3 * a + 2]]);
            let (nut, nrt) = (ut[0].hypot(ut[1]), rt[0].hypot(rt[1]));
            let m = mu[a];
            assert!(un >= -tol * su, "contact {a}: penetration u_N = {un:e}");
            assert!(rn >= 0.0, "contact {a}: r_N = {rn:e}");
            assert!(nrt <= m * rn + tol * sr, "contact {a}: ‖r_T‖ = {nrt:e} > μ r_N = {:e}", m * rn);
            let ut_n = un + m * nut;
            assert!(m * nut <= ut_n + tol * su, "contact {a}: ũ outside K*_μ");
            let compl = rn * ut_n + rt[0] * ut[0] + rt[1] * ut[1];
            assert!(compl.abs() <= tol * sr * su, "contact {a}: rᵀũ = {compl:e}");
            assert!((rn * un).abs() <= tol * sr * su, "contact {a}: r_N u_N = {:e}", rn * un);
            if rn > tol * sr {
                touching += 1;
                if nut > 1e-6 * su {
                    sliding += 1;
                } else {
                    sticking += 1;
                }
            }
        }
        assert!(touching > 0 && sliding > 0 && sticking > 0, "in contact {touching}, sliding {sliding}, sticking {sticking}");
        // r is our λ reordered, v our u
        let rec = dual.recover(&sol.lambda);
        assert_eq!(v, rec.u.concat());
        for a in 0..nc {
            assert_eq!(r[3 * a], sol.lambda[dual.layout.normal(a)]);
            assert_eq!([r[3 * a + 1], r[3 * a + 2]], [sol.lambda[dual.layout.tangent(a, 0)], sol.lambda[dual.layout.tangent(a, 1)]]);
            // the normal entry of u is the gap c − Bu
            assert!((u2[3 * a] - rec.gap[dual.layout.normal(a)]).abs() <= 1e-12 * su);
        }
        drop(file);
        let _ = std::fs::remove_dir_all(path.parent().unwrap());
    }

    #[test]
    fn bodies_gathered_from_several_ranks_assemble_in_body_order() {
        // under MPI body b lives on rank b % size: rank 0 may hold body 1 and another rank
        // body 0, a rank may hold none; rank 0 must assemble the same problem as one process
        let (_, model, bodies) = seed("{type=\"coulomb\", mu=0.3}");
        let contact = model.pairs.as_ref().unwrap();
        let (dual, _) = MonolithicDual::new(&SerialComm, contact, bodies);
        assert_eq!(dual.blocks.len(), 2);
        let lambda: Vec<f64> = (0..dual.dim()).map(|k| 1e-3 * (k % 7) as f64).collect();
        let u = dual.recover(&lambda).u;
        let one = |k: usize| pack(std::iter::once((&dual.blocks[k], u[k].as_slice())));
        let serial = unpack(&[pack(dual.blocks.iter().zip(u.iter().map(Vec::as_slice)))]);
        let ranks = unpack(&[one(1), pack(std::iter::empty()), one(0)]);
        assert_eq!(ranks.iter().map(|p| p.body).collect::<Vec<_>>(), [0, 1]);
        let (pos, mu) = (fclib_positions(&dual), vec![0.3; contact.len()]);
        let a = assemble(&serial, &pos, dual.c(), &lambda, mu.clone());
        let b = assemble(&ranks, &pos, dual.c(), &lambda, mu);
        assert_eq!(a, b);
        assert_eq!(a.v, u.concat());
        let n = dual.blocks.iter().map(|blk| blk.local.dofs.nfree).sum::<usize>();
        assert_eq!((a.m.m, a.m.n, a.h.m, a.h.n, a.f.len()), (n, n, n, 3 * contact.len(), n));
        // M whole: every off-diagonal entry of the lower triangles twice
        let lower: usize = dual.blocks.iter().map(|blk| blk.local.sys.k.nnz()).sum();
        assert_eq!(a.m.vals.len(), 2 * lower - n);
    }

    #[test]
    fn refuses_what_fclib_cannot_hold_and_leaves_no_file() {
        for friction in ["{type=\"coulomb\", mu1=0.2, mu2=0.1, direction=[1.0, 0.0, 0.0]}", "{type=\"tresca\", g=0.09}"] {
            let (ls, model, bodies) = seed(friction);
            let contact = model.pairs.as_ref().unwrap();
            let (dual, _) = MonolithicDual::new(&SerialComm, contact, bodies);
            let path = tmp("refused.h5");
            let e = write_global(&SerialComm, &path, &dual, contact, &vec![0.0; dual.dim()], &ls.scene.title).unwrap_err();
            assert!(e.to_string().starts_with("output.export_fclib: ") && e.to_string().contains("isotropic Coulomb"), "{e}");
            assert!(!path.exists() && !tmp("refused.h5.tmp").exists());
        }
        // a target that cannot be replaced (a directory): the error names it, no temporary left
        let (ls, model, bodies) = seed("{type=\"coulomb\", mu=0.3}");
        let contact = model.pairs.as_ref().unwrap();
        let (dual, _) = MonolithicDual::new(&SerialComm, contact, bodies);
        let dir = tmp("a_directory");
        std::fs::create_dir_all(&dir).unwrap();
        let e = write_global(&SerialComm, &dir, &dual, contact, &vec![0.0; dual.dim()], &ls.scene.title).unwrap_err();
        assert!(e.to_string().contains("a_directory"), "{e}");
        assert!(dir.is_dir() && !tmp("a_directory.tmp").exists());
        let _ = std::fs::remove_dir_all(&dir);
        // a λ of the wrong length
        let e = write_global(&SerialComm, &tmp("short.h5"), &dual, contact, &[0.0; 3], "t").unwrap_err();
        assert!(e.to_string().contains("λ has 3 entries"), "{e}");
    }
}
