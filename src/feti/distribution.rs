//! How the multipliers λ are spread over the ranks, and the communication of one A-product.
//!
//! Every multiplier row r has an **owner subdomain** o(r): the lowest-index subdomain whose B
//! rows touch it (for a contact pair, that of its normal row, so λν,ᵢ and λ̄τ,ᵢ stay together),
//! and lives on the rank of o(r). A rank's dual vectors hold only its **owned** rows, in global
//! order, so the solvers see a smaller [`Layout`] of the same shape (its pairs, then its λ_E).
//! Its subdomains also read the **ghost** rows owned by neighbours; together they are the
//! **local rows**. One A-product needs three neighbour exchanges ([`Distribution::ghosted`]:
//! owned → ghosts, twice; [`Distribution::assemble`]: the subdomains' contributions B_s z_s →
//! owners) and two reductions of a coarse vector (6 per subdomain); never an all-gather of λ.
//!
//! **Results do not depend on the rank count, bit for bit.** Every sum is taken in an order
//! fixed by the decomposition alone: a row of B z sums its subdomains' contributions in
//! ascending subdomain order (each contribution travels on its own); a coarse vector is
//! reduced with one contributing rank per entry (x + 0 is exact); a dot product sums per owner
//! subdomain, reduces those partial sums (one contributor each) and adds them in subdomain
//! order. So 1, 2 or 3 ranks take the same branches and give the same digits.

use std::cell::Cell;
use std::time::Instant;

use crate::comm::Comm;
use crate::qp::{Layout, Space};

use super::constraints::Constraints;

/// Seconds spent in the parts of the A-products and solver reductions on this rank.
#[derive(Debug, Default)]
pub struct Clock {
    /// K_s⁺ solves.
    pub pinv: Cell<f64>,
    /// Neighbour exchanges (waiting for the neighbours included).
    pub exchange: Cell<f64>,
    /// Reductions: coarse vectors and dot products.
    pub reduce: Cell<f64>,
    /// C⁻¹ (and (GGᵀ)⁻¹) solves of the projectors P̃ and P.
    pub coarse_solve: Cell<f64>,
    /// Whole projections onto Ker G ∩ W in the inner solves (exchange, G x, (GΠGᵀ)⁻¹, Gᵀa) and
    /// the factorizations of GΠGᵀ.
    pub restricted: Cell<f64>,
    /// The part of `restricted` spent factorizing GΠGᵀ.
    pub restricted_factor: Cell<f64>,
    /// Whole A-products.
    pub apply: Cell<f64>,
}

impl Clock {
    /// Runs `f`, adding its time to `cell`.
    pub fn time<T>(cell: &Cell<f64>, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let r = f();
        cell.set(cell.get() + t0.elapsed().as_secs_f64());
        r
    }
}

/// Where one entry of a subdomain's contribution goes.
#[derive(Clone, Copy, Debug)]
enum Dest {
    /// A slot of an owned row on this rank.
    Slot(usize),
    /// Position in the message to neighbour `send[q]`.
    Send(usize, usize),
}

/// A subdomain of this rank: its rows (positions in the local rows, ascending global order)
/// and where its contributions go.
#[derive(Clone, Debug)]
pub struct SubRows {
    /// Global index of the subdomain.
    pub index: usize,
    /// Local-row position of each of its rows (the same order as `Constraints::sorted_rows`).
    pub rows: Vec<usize>,
    dest: Vec<Dest>,
}

/// The ownership of the multipliers and the exchange plans of this rank.
pub struct Distribution<'c, C: Comm> {
    comm: &'c C,
    /// The solvers' layout of the owned rows.
    pub layout: Layout,
    /// Owned rows (global indices, ascending).
    pub owned: Vec<usize>,
    /// Owned contact pairs (global pair indices, ascending).
    pub pairs: Vec<usize>,
    /// Local rows: owned and ghosts (global, ascending).
    pub local_rows: Vec<usize>,
    /// Local-row position of each owned row.
    pub owned_pos: Vec<usize>,
    /// Owner subdomain of each owned row (the dot products' partial sums).
    chunk: Vec<usize>,
    subdomains: usize,
    /// This rank's subdomains, ascending.
    pub subs: Vec<SubRows>,
    /// Per local row: the subdomains touching it, ascending, as (subdomain, position in its
    /// sorted rows) in `touch[touch_ptr[l]..touch_ptr[l + 1]]`.
    touch_ptr: Vec<usize>,
    touch: Vec<(usize, usize)>,
    /// Forward exchange: owned positions sent to each neighbour, local-row positions received.
    fwd_send: Vec<(usize, Vec<usize>)>,
    fwd_recv: Vec<(usize, Vec<usize>)>,
    /// Reverse exchange: message lengths per neighbour, the slots received values go to.
    rev_send: Vec<(usize, usize)>,
    rev_recv: Vec<(usize, Vec<usize>)>,
    /// Slots of owned row k: `slot_ptr[k]..slot_ptr[k + 1]`, one per touching subdomain.
    slot_ptr: Vec<usize>,
    pub clock: Clock,
}

impl<'c, C: Comm> Distribution<'c, C> {
    /// The plan of this rank for the constraint rows `cons` and the subdomains' ranks `owner`.
    pub fn new(comm: &'c C, cons: &Constraints, owner: &[usize]) -> Self {
        let me = comm.rank();
        let ns = owner.len();
        let n = cons.layout.dim();
        let sorted: Vec<Vec<usize>> = (0..ns).map(|s| cons.sorted_rows(s)).collect();
        // subdomains touching each row, ascending
        let mut row_subs: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
        for (s, rows) in sorted.iter().enumerate() {
            for (p, &r) in rows.iter().enumerate() {
                row_subs[r].push((s, p));
            }
        }
        let g = cons.layout;
        let owner_sub = |r: usize| -> usize {
            // a pair's tangential rows follow its normal row
            let r = if g.friction && r >= g.m && r < g.contact_dim() { (r - g.m) / 2 } else { r };
            row_subs[r].first().expect("every multiplier row touches a subdomain").0
        };
        let row_rank = |r: usize| owner[owner_sub(r)];
        let owned: Vec<usize> = (0..n).filter(|&r| row_rank(r) == me).collect();
        let chunk: Vec<usize> = owned.iter().map(|&r| owner_sub(r)).collect();
        let pairs: Vec<usize> = owned.iter().copied().take_while(|&r| r < g.m).collect();
        let free = owned.iter().filter(|&&r| r >= g.contact_dim()).count();
        let layout = Layout { m: pairs.len(), friction: g.friction, free };
        let mine: Vec<usize> = (0..ns).filter(|&s| owner[s] == me).collect();
        let mut local_rows: Vec<usize> = mine.iter().flat_map(|&s| sorted[s].iter().copied()).collect();
        local_rows.sort_unstable();
        local_rows.dedup();
        let pos = |r: usize| local_rows.binary_search(&r).expect("a row of this rank's subdomains");
        let owned_pos: Vec<usize> = owned.iter().map(|&r| pos(r)).collect();
        let mut touch_ptr = vec![0];
        let mut touch = Vec::new();
        for &r in &local_rows {
            touch.extend(&row_subs[r]);
            touch_ptr.push(touch.len());
        }
        // slots of the owned rows
        let mut slot_ptr = vec![0];
        for &r in &owned {
            slot_ptr.push(slot_ptr.last().unwrap() + row_subs[r].len());
        }
        let owned_index = |r: usize| owned.binary_search(&r).ok();
        let slot_of = |r: usize, s: usize| -> usize {
            let k = owned_index(r).expect("owned row");
            slot_ptr[k] + row_subs[r].iter().position(|x| x.0 == s).expect("subdomain touches row")
        };
        // forward: owned rows that neighbours' subdomains read; ghosts this rank reads
        let mut fwd_send: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for (k, &r) in owned.iter().enumerate() {
            for &(s, _) in &row_subs[r] {
                let q = owner[s];
                if q != me {
                    let list = fwd_send.entry(q).or_default();
                    if list.last() != Some(&k) {
                        list.push(k);
                    }
                }
            }
        }
        let mut fwd_recv: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for (l, &r) in local_rows.iter().enumerate() {
            let q = row_rank(r);
            if q != me {
                fwd_recv.entry(q).or_default().push(l);
            }
        }
        // reverse: each subdomain's contribution to each of its rows, to the row's owner
        let mut rev_len: std::collections::BTreeMap<usize, usize> = Default::default();
        let subs: Vec<SubRows> = mine
            .iter()
            .map(|&s| {
                let dest = sorted[s]
                    .iter()
                    .map(|&r| match row_rank(r) {
                        q if q == me => Dest::Slot(slot_of(r, s)),
                        q => {
                            let len = rev_len.entry(q).or_default();
                            *len += 1;
                            Dest::Send(q, *len - 1)
                        }
                    })
                    .collect();
                SubRows { index: s, rows: sorted[s].iter().map(|&r| pos(r)).collect(), dest }
            })
            .collect();
        let mut rev_recv: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for (s, rows) in sorted.iter().enumerate().filter(|(s, _)| owner[*s] != me) {
            for &r in rows {
                if row_rank(r) == me {
                    rev_recv.entry(owner[s]).or_default().push(slot_of(r, s));
                }
            }
        }
        let rev_send: Vec<(usize, usize)> = rev_len.into_iter().collect();
        // Dest::Send(q, i) → index of q in rev_send
        let subs = subs
            .into_iter()
            .map(|mut sr| {
                for d in &mut sr.dest {
                    if let Dest::Send(q, i) = *d {
                        *d = Dest::Send(rev_send.iter().position(|x| x.0 == q).expect("neighbour"), i);
                    }
                }
                sr
            })
            .collect();
        Distribution {
            comm,
            layout,
            owned,
            pairs,
            local_rows,
            owned_pos,
            chunk,
            subdomains: ns,
            subs,
            touch_ptr,
            touch,
            fwd_send: fwd_send.into_iter().collect(),
            fwd_recv: fwd_recv.into_iter().collect(),
            rev_send,
            rev_recv: rev_recv.into_iter().collect(),
            slot_ptr,
            clock: Clock::default(),
        }
    }

    pub fn comm(&self) -> &'c C {
        self.comm
    }

    /// Number of local rows.
    pub fn local_len(&self) -> usize {
        self.local_rows.len()
    }

    /// The subdomains touching local row `l`, ascending: (subdomain, position in its rows).
    pub fn touching(&self, l: usize) -> &[(usize, usize)] {
        &self.touch[self.touch_ptr[l]..self.touch_ptr[l + 1]]
    }

    /// Values this rank sends per forward exchange and per reverse exchange, and its number of
    /// neighbours.
    pub fn message_sizes(&self) -> (usize, usize, usize) {
        let fwd = self.fwd_send.iter().map(|x| x.1.len()).sum();
        let rev = self.rev_send.iter().map(|x| x.1).sum();
        let mut n: Vec<usize> = self.fwd_send.iter().map(|x| x.0).chain(self.fwd_recv.iter().map(|x| x.0)).chain(self.rev_send.iter().map(|x| x.0)).collect();
        n.sort_unstable();
        n.dedup();
        (fwd, rev, n.len())
    }

    /// The owned vector `x` on the local rows (owned values, ghosts from their owners).
    pub fn ghosted(&self, x: &[f64]) -> Vec<f64> {
        let mut xl = vec![0.0; self.local_len()];
        for (&p, &v) in self.owned_pos.iter().zip(x) {
            xl[p] = v;
        }
        let send: Vec<(usize, Vec<f64>)> = self.fwd_send.iter().map(|(q, ks)| (*q, ks.iter().map(|&k| x[k]).collect())).collect();
        let mut recv: Vec<(usize, Vec<f64>)> = self.fwd_recv.iter().map(|(q, ls)| (*q, vec![0.0; ls.len()])).collect();
        Clock::time(&self.clock.exchange, || self.comm.exchange(&send, &mut recv));
        for ((_, ls), (_, buf)) in self.fwd_recv.iter().zip(&recv) {
            for (&l, &v) in ls.iter().zip(buf) {
                xl[l] = v;
            }
        }
        xl
    }

    /// The owned part of a local-rows vector.
    pub fn owned_part(&self, xl: &[f64]) -> Vec<f64> {
        self.owned_pos.iter().map(|&p| xl[p]).collect()
    }

    /// y = Σ_s v_s on the owned rows, `v[j]` being the contribution of `subs[j]` to each of its
    /// rows; every row sums its subdomains in ascending order.
    pub fn assemble(&self, v: &[Vec<f64>], y: &mut [f64]) {
        let mut slots = vec![0.0; *self.slot_ptr.last().unwrap()];
        let mut send: Vec<(usize, Vec<f64>)> = self.rev_send.iter().map(|&(q, len)| (q, vec![0.0; len])).collect();
        for (sr, vs) in self.subs.iter().zip(v) {
            for (d, &x) in sr.dest.iter().zip(vs) {
                match *d {
                    Dest::Slot(i) => slots[i] = x,
                    Dest::Send(q, i) => send[q].1[i] = x,
                }
            }
        }
        let mut recv: Vec<(usize, Vec<f64>)> = self.rev_recv.iter().map(|(q, ss)| (*q, vec![0.0; ss.len()])).collect();
        Clock::time(&self.clock.exchange, || self.comm.exchange(&send, &mut recv));
        for ((_, ss), (_, buf)) in self.rev_recv.iter().zip(&recv) {
            for (&i, &x) in ss.iter().zip(buf) {
                slots[i] = x;
            }
        }
        for (k, yk) in y.iter_mut().enumerate() {
            *yk = slots[self.slot_ptr[k]..self.slot_ptr[k + 1]].iter().sum();
        }
    }

    /// Sums a coarse-sized vector over the ranks; exact when each entry comes from one rank.
    pub fn reduce(&self, a: &mut [f64]) {
        Clock::time(&self.clock.reduce, || self.comm.sum_f64(a));
    }

    /// Dot product of two owned vectors, independent of the rank count (module doc).
    pub fn dot(&self, x: &[f64], y: &[f64]) -> f64 {
        let mut partial = vec![0.0; self.subdomains];
        for ((&c, a), b) in self.chunk.iter().zip(x).zip(y) {
            partial[c] += a * b;
        }
        Clock::time(&self.clock.reduce, || self.comm.sum_f64(&mut partial));
        partial.iter().sum()
    }

    /// [`Distribution::dot`] of several pairs in one reduction (each the same value `dot` gives).
    pub fn dots(&self, pairs: &[(&[f64], &[f64])], out: &mut [f64]) {
        let s = self.subdomains;
        let mut partial = vec![0.0; s * pairs.len()];
        for (j, (x, y)) in pairs.iter().enumerate() {
            let p = &mut partial[j * s..(j + 1) * s];
            for ((&c, a), b) in self.chunk.iter().zip(x.iter()).zip(y.iter()) {
                p[c] += a * b;
            }
        }
        Clock::time(&self.clock.reduce, || self.comm.sum_f64(&mut partial));
        for (j, o) in out.iter_mut().enumerate() {
            *o = partial[j * s..(j + 1) * s].iter().sum();
        }
    }

    /// The owned components of a vector over all rows.
    pub fn restrict(&self, global: &[f64]) -> Vec<f64> {
        self.owned.iter().map(|&r| global[r]).collect()
    }

    /// The first `n` rows of a distributed vector, whole on every rank (each rank's owned
    /// entries summed in: exact, one contributor per entry).
    pub fn all_rows(&self, x: &[f64], n: usize) -> Vec<f64> {
        let mut g = vec![0.0; n];
        for (&r, &v) in self.owned.iter().zip(x).take_while(|(&r, _)| r < n) {
            g[r] = v;
        }
        self.comm.sum_f64(&mut g);
        g
    }
}

/// The solvers' reductions over TFETI's distributed dual vectors.
impl<C: Comm> Space for Distribution<'_, C> {
    fn dot(&self, x: &[f64], y: &[f64]) -> f64 {
        Distribution::dot(self, x, y)
    }

    fn dots(&self, pairs: &[(&[f64], &[f64])], out: &mut [f64]) {
        Distribution::dots(self, pairs, out)
    }

    fn max(&self, v: f64) -> f64 {
        let mut a = [v];
        self.comm.max_f64(&mut a);
        a[0]
    }

    fn count(&self, n: usize) -> usize {
        let mut a = [n as u64];
        self.comm.sum_u64(&mut a);
        a[0] as usize
    }

    fn global_index(&self, i: usize) -> usize {
        self.owned[i]
    }
}
