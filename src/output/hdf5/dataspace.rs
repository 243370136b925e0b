//! The rows each rank writes and how: contiguous [`block`]s of every dataset's rows, the rows
//! of a distributed field sent to the rank whose block holds them ([`gather_block`], one
//! all-to-all exchange), and the collective hyperslab writes ([`write_dataset`], [`write_rows`]).

use ::hdf5::{Dataset, Group, H5Type};

use super::write::Writer;
use super::{ctx, h5_text};
use crate::comm::Comm;
use crate::error::{Error, Result};

/// The rows `[lo, hi)` of `len` that rank `rank` of `size` writes: contiguous blocks in rank
/// order, the ranks' shares as even as can be.
pub(super) fn block(len: usize, rank: usize, size: usize) -> (usize, usize) {
    (len * rank / size, len * (rank + 1) / size)
}

/// The rank whose [`block`] holds row `row` (< `len`).
pub(super) fn block_owner(row: usize, len: usize, size: usize) -> usize {
    ((row + 1) * size - 1) / len
}

/// Element types of the datasets, carried bit for bit through [`Comm::all_to_all_u64`].
pub(super) trait Bits: H5Type + Copy + Default {
    fn to_u64(self) -> u64;
    fn from_u64(b: u64) -> Self;
}

impl Bits for f64 {
    fn to_u64(self) -> u64 {
        self.to_bits()
    }
    fn from_u64(b: u64) -> Self {
        f64::from_bits(b)
    }
}

impl Bits for i32 {
    fn to_u64(self) -> u64 {
        u64::from(self as u32)
    }
    fn from_u64(b: u64) -> Self {
        b as u32 as i32
    }
}

impl Bits for i64 {
    fn to_u64(self) -> u64 {
        self as u64
    }
    fn from_u64(b: u64) -> Self {
        b as i64
    }
}

/// This rank's [`block`] of a distributed field of `len` rows × `ncomp`, from the rows each rank
/// holds (`rows`, values `v` in their order): one all-to-all exchange, each row sent to the rank
/// whose block has it. Rows no rank holds are 0 (HDF5's fill value); a row held twice gets the
/// values of its last holder (by rank, then by position).
pub(super) fn gather_block<T: Bits, C: Comm>(comm: &C, len: usize, ncomp: usize, rows: &[usize], v: &[T]) -> Vec<T> {
    let size = comm.size();
    let mut counts = vec![0usize; size];
    for &r in rows {
        counts[block_owner(r, len, size)] += 1 + ncomp;
    }
    let mut send: Vec<Vec<u64>> = counts.iter().map(|&n| Vec::with_capacity(n)).collect();
    for (&r, x) in rows.iter().zip(v.chunks_exact(ncomp)) {
        let m = &mut send[block_owner(r, len, size)];
        m.push(r as u64);
        m.extend(x.iter().map(|&y| y.to_u64()));
    }
    let (lo, hi) = block(len, comm.rank(), size);
    let mut out = vec![T::default(); (hi - lo) * ncomp];
    for m in comm.all_to_all_u64(&send) {
        for rec in m.chunks_exact(1 + ncomp) {
            let at = (rec[0] as usize - lo) * ncomp;
            for (o, &b) in out[at..at + ncomp].iter_mut().zip(&rec[1..]) {
                *o = T::from_u64(b);
            }
        }
    }
    out
}

/// Creates the dataset `name` of the global `shape` (len or len × ncomp) and writes this
/// rank's [`block`] of its rows as one hyperslab: taken from `v` where it is replicated (rows
/// None), gathered by [`gather_block`] from every rank's rows `rows` (values `v` in their order)
/// where it is distributed. Collective (a rank with nothing to write still takes part with an
/// empty selection), and through collective MPI-IO transfers under MPI.
pub(super) fn write_dataset<T: Bits, C: Comm>(
    w: &Writer<'_, C>,
    group: &Group,
    name: &str,
    shape: &[usize],
    rows: Option<&[usize]>,
    v: &[T],
) -> Result<Dataset> {
    let ncomp = shape.get(1).copied().unwrap_or(1);
    let (lo, hi) = block(shape[0], w.comm.rank(), w.comm.size());
    let gathered;
    let vals = match rows {
        Some(r) => {
            gathered = gather_block(w.comm, shape[0], ncomp, r, v);
            &gathered[..]
        }
        None => &v[lo * ncomp..hi * ncomp],
    };
    write_rows(w, group, name, shape, lo, hi, vals)
}

/// Creates the dataset `name` of the global `shape` and writes the rows `[lo, hi)` of it from
/// `vals` (`(hi − lo) × ncomp` values) as one hyperslab. Collective, like [`write_dataset`]:
/// every rank calls it, each with its own rows (possibly none); the ranks' rows must not
/// overlap.
pub(super) fn write_rows<T: Bits, C: Comm>(w: &Writer<'_, C>, group: &Group, name: &str, shape: &[usize], lo: usize, hi: usize, vals: &[T]) -> Result<Dataset> {
    use hdf5_sys::h5::hsize_t;
    use hdf5_sys::h5d::{H5Dget_space, H5Dwrite};
    use hdf5_sys::h5p::{H5FD_mpio_xfer_t, H5Pclose, H5Pcreate, H5Pset_dxpl_mpio, H5P_CLS_DATASET_XFER, H5P_DEFAULT};
    use hdf5_sys::h5s::{H5S_seloper_t, H5Sclose, H5Screate_simple, H5Sselect_hyperslab, H5Sselect_none};
    let what = || format!("dataset {}/{name}", group.name());
    let ncomp = shape.get(1).copied().unwrap_or(1);
    let ds = w.all(group.new_dataset::<T>().shape(shape.to_vec()).create(name).map_err(|e| ctx(format!("creating {}", what()))(e)))?;
    let mem_type = w.all(::hdf5::Datatype::from_type::<T>().map_err(|e| ctx(format!("datatype of {}", what()))(e)))?;
    let collective = w.comm.mpi_comm().is_some();
    // SAFETY: plain HDF5 C calls on ids this function owns (closed below) or that `ds` keeps
    // alive; the buffer holds `vals.len()` elements of `T`, matching the memory space. They run
    // under hdf5-metno's global lock, like its own calls (HDF5 is not thread-safe).
    let status = ::hdf5::sync::sync(|| unsafe {
        let fspace = H5Dget_space(ds.id());
        if hi > lo {
            let start = [lo as hsize_t, 0];
            let count = [(hi - lo) as hsize_t, ncomp as hsize_t];
            H5Sselect_hyperslab(fspace, H5S_seloper_t::H5S_SELECT_SET, start.as_ptr(), std::ptr::null(), count.as_ptr(), std::ptr::null());
        } else {
            H5Sselect_none(fspace);
        }
        let mdims = [vals.len().max(1) as hsize_t];
        let mspace = H5Screate_simple(1, mdims.as_ptr(), std::ptr::null());
        if vals.is_empty() {
            H5Sselect_none(mspace);
        }
        let dxpl = if collective {
            let d = H5Pcreate(*H5P_CLS_DATASET_XFER);
            H5Pset_dxpl_mpio(d, H5FD_mpio_xfer_t::H5FD_MPIO_COLLECTIVE);
            d
        } else {
            H5P_DEFAULT
        };
        // HDF5 wants a non-null buffer even when nothing is selected
        let one = std::mem::MaybeUninit::<T>::uninit();
        let buf = if vals.is_empty() { one.as_ptr() } else { vals.as_ptr() };
        let st = H5Dwrite(ds.id(), mem_type.id(), mspace, fspace, dxpl, buf.cast());
        // the reason, read off HDF5's error stack before another call clears it
        let why = (st < 0).then(|| ::hdf5::Error::query().map_or_else(|e| e.to_string(), |e| h5_text(&e)));
        if collective {
            H5Pclose(dxpl);
        }
        H5Sclose(mspace);
        H5Sclose(fspace);
        why
    });
    // one rank's failed share of a collective write stops every rank here
    w.all(match status {
        Some(why) => Err(Error::output(String::new(), format!("writing {}: {why}{}", what(), w.no_space(std::mem::size_of_val(vals) as u64)))),
        None => Ok(()),
    })?;
    Ok(ds)
}
