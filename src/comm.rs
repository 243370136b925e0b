//! The communicator layer: every reduction, broadcast and gather of the program goes through the
//! [`Comm`] trait, so that the same code runs serially ([`SerialComm`], used by unit tests, which
//! must not initialize MPI) and under `mpirun` ([`MpiComm`]). Branch decisions are taken on
//! reduced values ([`Comm::agree`]) so that all ranks follow the same path.

use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Count;

use crate::error::{Error, Result};

/// Collective operations the solver needs. Every rank must call them in the same order.
pub trait Comm {
    /// This rank's number, 0 ≤ rank < size.
    fn rank(&self) -> usize;
    /// Number of ranks.
    fn size(&self) -> usize;
    /// Element-wise sum over all ranks, in place.
    fn sum_f64(&self, v: &mut [f64]);
    /// Element-wise maximum over all ranks, in place.
    fn max_f64(&self, v: &mut [f64]);
    /// Element-wise sum over all ranks, in place.
    fn sum_u64(&self, v: &mut [u64]);
    /// Replaces `buf` on every rank by `buf` of `root`.
    fn broadcast_bytes(&self, root: usize, buf: &mut Vec<u8>);
    /// The `local` slices of all ranks, in rank order, on `root` (None elsewhere).
    fn gather_f64(&self, root: usize, local: &[f64]) -> Option<Vec<Vec<f64>>>;
    /// The `local` slices of all ranks, in rank order, on every rank.
    fn all_gather_f64(&self, local: &[f64]) -> Vec<Vec<f64>>;
    /// Neighbour exchange: sends `send[k].1` to rank `send[k].0` and fills each `recv[k].1`
    /// (sized by the caller) from rank `recv[k].0`. Ranks list each neighbour once; both
    /// sides must agree on the sizes. Only the ranks named take part (no collective).
    fn exchange(&self, send: &[(usize, Vec<f64>)], recv: &mut [(usize, Vec<f64>)]);
    /// Personalized all-to-all: sends `send[q]` (any length, one per rank) to rank q and
    /// returns what every rank sent this one, in rank order. Collective.
    fn all_to_all_u64(&self, send: &[Vec<u64>]) -> Vec<Vec<u64>>;
    /// Waits until every rank has reached it.
    fn barrier(&self);
    /// The MPI communicator handle, for libraries that take one (MPI-IO); None without MPI.
    fn mpi_comm(&self) -> Option<mpi::ffi::MPI_Comm> {
        None
    }
    /// Name and version of the MPI library ("serial" without MPI).
    fn library(&self) -> String;

    /// Whether this is rank 0.
    fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// Global dot product of distributed vectors.
    fn dot(&self, a: &[f64], b: &[f64]) -> f64 {
        let mut s = [a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>()];
        self.sum_f64(&mut s);
        s[0]
    }

    /// Global Euclidean norm of a distributed vector.
    fn norm(&self, a: &[f64]) -> f64 {
        self.dot(a, a).sqrt()
    }

    /// Makes a rank-local result collective: if any rank failed, every rank returns the error of
    /// the lowest failing rank (its message travels to all), so all ranks stop together.
    fn agree<T>(&self, local: Result<T>) -> Result<T> {
        let mut failed = vec![0u64; self.size()];
        failed[self.rank()] = u64::from(local.is_err());
        self.sum_u64(&mut failed);
        let Some(first) = failed.iter().position(|&f| f != 0) else {
            return local;
        };
        let mut msg = match &local {
            Err(e) if self.rank() == first => e.to_string().into_bytes(),
            _ => Vec::new(),
        };
        self.broadcast_bytes(first, &mut msg);
        match local {
            Err(e) if self.rank() == first => Err(e),
            _ => Err(Error::Remote(String::from_utf8_lossy(&msg).into_owned())),
        }
    }
}

/// One process, no MPI.
#[derive(Clone, Copy, Debug, Default)]
pub struct SerialComm;

impl Comm for SerialComm {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn sum_f64(&self, _: &mut [f64]) {}
    fn max_f64(&self, _: &mut [f64]) {}
    fn sum_u64(&self, _: &mut [u64]) {}
    fn broadcast_bytes(&self, _: usize, _: &mut Vec<u8>) {}
    fn gather_f64(&self, _: usize, local: &[f64]) -> Option<Vec<Vec<f64>>> {
        Some(vec![local.to_vec()])
    }
    fn all_gather_f64(&self, local: &[f64]) -> Vec<Vec<f64>> {
        vec![local.to_vec()]
    }
    fn exchange(&self, send: &[(usize, Vec<f64>)], recv: &mut [(usize, Vec<f64>)]) {
        // one rank has no neighbours
        assert!(send.is_empty() && recv.is_empty(), "SerialComm has no neighbours");
    }
    fn all_to_all_u64(&self, send: &[Vec<u64>]) -> Vec<Vec<u64>> {
        assert_eq!(send.len(), 1, "SerialComm: one message per rank");
        send.to_vec()
    }
    fn barrier(&self) {}
    fn library(&self) -> String {
        "serial".into()
    }
}

/// MPI through rsmpi.
pub struct MpiComm {
    world: SimpleCommunicator,
}

impl MpiComm {
    /// The communicator of `world`.
    pub fn new(world: SimpleCommunicator) -> Self {
        MpiComm { world }
    }

    /// The rsmpi communicator.
    pub fn raw(&self) -> &SimpleCommunicator {
        &self.world
    }
}

/// The most values one rank sends per round of [`Comm::gather_f64`] with `p` ranks: (2³¹ − 1)/p,
/// or `TRESCA_FETI_GATHER_CHUNK` when set (to test the rounds on small models).
fn gather_chunk(p: usize) -> usize {
    let most = i32::MAX as usize / p.max(1);
    std::env::var("TRESCA_FETI_GATHER_CHUNK").ok().and_then(|v| v.parse::<usize>().ok()).filter(|&c| c > 0).map_or(most, |c| c.min(most))
}

/// The rounds that move messages of `lens` values in pieces of at most `chunk`.
fn rounds(lens: impl Iterator<Item = usize>, chunk: usize) -> usize {
    lens.map(|n| n.div_ceil(chunk)).max().unwrap_or(0)
}

/// The values of a message of `n` that round `k` moves (at most `chunk` ≤ i32::MAX).
fn round_part(n: usize, k: usize, chunk: usize) -> Count {
    n.saturating_sub(k * chunk).min(chunk) as Count
}

/// The displacements of `counts` laid end to end (their total is at most p · chunk ≤ i32::MAX).
fn displacements(counts: &[Count]) -> Vec<Count> {
    counts
        .iter()
        .scan(0 as Count, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect()
}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.world.rank() as usize
    }
    fn size(&self) -> usize {
        self.world.size() as usize
    }
    fn sum_f64(&self, v: &mut [f64]) {
        let send = v.to_vec();
        self.world.all_reduce_into(&send[..], v, mpi::collective::SystemOperation::sum());
    }
    fn max_f64(&self, v: &mut [f64]) {
        let send = v.to_vec();
        self.world.all_reduce_into(&send[..], v, mpi::collective::SystemOperation::max());
    }
    fn sum_u64(&self, v: &mut [u64]) {
        let send = v.to_vec();
        self.world.all_reduce_into(&send[..], v, mpi::collective::SystemOperation::sum());
    }
    fn broadcast_bytes(&self, root: usize, buf: &mut Vec<u8>) {
        let root = self.world.process_at_rank(root as i32);
        let mut len = [buf.len() as u64];
        root.broadcast_into(&mut len[..]);
        buf.resize(len[0] as usize, 0);
        // an empty buffer is a null pointer to MPI (MPI_ERR_ARG): nothing to send then
        if !buf.is_empty() {
            root.broadcast_into(&mut buf[..]);
        }
    }
    fn gather_f64(&self, root: usize, local: &[f64]) -> Option<Vec<Vec<f64>>> {
        // MPI counts and displacements are i32: the values go in rounds of at most
        // `gather_chunk()` per rank, so that no round's total passes 2³¹ − 1 (one round for
        // any field of a model under 2³¹ values)
        let r = self.world.process_at_rank(root as i32);
        let p = self.size();
        let mut lens = vec![0u64; p];
        self.world.all_gather_into(&(local.len() as u64), &mut lens[..]);
        let chunk = gather_chunk(p);
        let mut out: Vec<Vec<f64>> = if self.rank() == root { lens.iter().map(|&n| Vec::with_capacity(n as usize)).collect() } else { Vec::new() };
        for k in 0..rounds(lens.iter().map(|&n| n as usize), chunk) {
            let start = (k * chunk).min(local.len());
            let mine = &local[start..start + round_part(local.len(), k, chunk) as usize];
            if self.rank() == root {
                let counts: Vec<Count> = lens.iter().map(|&n| round_part(n as usize, k, chunk)).collect();
                let displs = displacements(&counts);
                let total: usize = counts.iter().map(|&c| c as usize).sum();
                // never an empty buffer (a null pointer to some MPI libraries): one unused value
                let mut all = vec![0.0; total.max(1)];
                {
                    let mut recv = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
                    r.gather_varcount_into_root(mine, &mut recv);
                }
                for (q, (&c, &d)) in counts.iter().zip(&displs).enumerate() {
                    out[q].extend_from_slice(&all[d as usize..(d + c) as usize]);
                }
            } else {
                r.gather_varcount_into(mine);
            }
        }
        (self.rank() == root).then_some(out)
    }
    fn all_gather_f64(&self, local: &[f64]) -> Vec<Vec<f64>> {
        // in rounds of at most `gather_chunk()` values per rank, as `gather_f64`
        let p = self.size();
        let mut lens = vec![0u64; p];
        self.world.all_gather_into(&(local.len() as u64), &mut lens[..]);
        let chunk = gather_chunk(p);
        let mut out: Vec<Vec<f64>> = lens.iter().map(|&n| Vec::with_capacity(n as usize)).collect();
        for k in 0..rounds(lens.iter().map(|&n| n as usize), chunk) {
            let counts: Vec<Count> = lens.iter().map(|&n| round_part(n as usize, k, chunk)).collect();
            let displs = displacements(&counts);
            let total: usize = counts.iter().map(|&c| c as usize).sum();
            let start = (k * chunk).min(local.len());
            let mine = &local[start..start + round_part(local.len(), k, chunk) as usize];
            // never an empty buffer (a null pointer to some MPI libraries): one unused value
            let mut all = vec![0.0; total.max(1)];
            {
                let mut part = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
                self.world.all_gather_varcount_into(mine, &mut part);
            }
            for (q, (&c, &d)) in counts.iter().zip(&displs).enumerate() {
                out[q].extend_from_slice(&all[d as usize..(d + c) as usize]);
            }
        }
        out
    }
    fn exchange(&self, send: &[(usize, Vec<f64>)], recv: &mut [(usize, Vec<f64>)]) {
        mpi::request::scope(|scope| {
            let mut recvs = Vec::with_capacity(recv.len());
            for (q, buf) in recv.iter_mut() {
                recvs.push(self.world.process_at_rank(*q as i32).immediate_receive_into(scope, &mut buf[..]));
            }
            let sends: Vec<_> = send.iter().map(|(q, buf)| self.world.process_at_rank(*q as i32).immediate_send(scope, &buf[..])).collect();
            for r in recvs {
                r.wait();
            }
            for s in sends {
                s.wait();
            }
        });
    }
    fn all_to_all_u64(&self, send: &[Vec<u64>]) -> Vec<Vec<u64>> {
        let p = self.size();
        assert_eq!(send.len(), p, "all_to_all_u64: one message per rank");
        // in rounds of at most `gather_chunk()` values per message: no count, displacement or
        // total of a round passes MPI's i32
        let lens: Vec<u64> = send.iter().map(|v| v.len() as u64).collect();
        let mut rlens = vec![0u64; p];
        self.world.all_to_all_into(&lens[..], &mut rlens[..]);
        let chunk = gather_chunk(p);
        let mine = rounds(lens.iter().chain(&rlens).map(|&n| n as usize), chunk) as u64;
        let mut most = [0u64];
        self.world.all_reduce_into(&[mine][..], &mut most[..], mpi::collective::SystemOperation::max());
        let mut out: Vec<Vec<u64>> = rlens.iter().map(|&n| Vec::with_capacity(n as usize)).collect();
        for k in 0..most[0] as usize {
            let scounts: Vec<Count> = send.iter().map(|v| round_part(v.len(), k, chunk)).collect();
            let rcounts: Vec<Count> = rlens.iter().map(|&n| round_part(n as usize, k, chunk)).collect();
            let (sdispls, rdispls) = (displacements(&scounts), displacements(&rcounts));
            let rtotal: usize = rcounts.iter().map(|&n| n as usize).sum();
            // never an empty buffer (a null pointer to some MPI libraries): one unused value then
            let mut sbuf: Vec<u64> =
                send.iter().zip(&scounts).flat_map(|(v, &c)| &v[(k * chunk).min(v.len())..(k * chunk).min(v.len()) + c as usize]).copied().collect();
            sbuf.push(0);
            let mut rbuf = vec![0u64; rtotal + 1];
            {
                let sp = Partition::new(&sbuf[..], &scounts[..], &sdispls[..]);
                let mut rp = PartitionMut::new(&mut rbuf[..], &rcounts[..], &rdispls[..]);
                self.world.all_to_all_varcount_into(&sp, &mut rp);
            }
            for (q, (&c, &d)) in rcounts.iter().zip(&rdispls).enumerate() {
                out[q].extend_from_slice(&rbuf[d as usize..(d + c) as usize]);
            }
        }
        out
    }
    fn barrier(&self) {
        self.world.barrier();
    }
    fn mpi_comm(&self) -> Option<mpi::ffi::MPI_Comm> {
        Some(self.world.as_raw())
    }
    fn library(&self) -> String {
        mpi::environment::library_version()
            .map(|s| s.trim_end_matches('\0').trim().lines().next().unwrap_or("").to_string())
            .unwrap_or_else(|_| "MPI (unknown version)".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serial_agree_passes_errors_through() {
        let c = SerialComm;
        assert_eq!(c.agree(Ok(3)).unwrap(), 3);
        let e = c.agree::<()>(Err(Error::scene("a.b", "bad"))).unwrap_err();
        assert_eq!(e.to_string(), "a.b: bad");
        assert_eq!(c.dot(&[1.0, 2.0], &[3.0, 4.0]), 11.0);
        assert_eq!(c.all_to_all_u64(&[vec![7, 8]]), [vec![7, 8]]);
    }
}
