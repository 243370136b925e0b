//! The scaling forecast of `tresca-feti check --hosts H`: the predicted time of each phase and
//! the parallel efficiency of the plan's chosen decomposition on P = 1, 2, 4, …, 4096 ranks,
//! from the plan's cost model ([`plan`]) and a network model read from a small TOML file
//! ([`Network`], shipped as run/network.toml).
//!
//! The model, on P ranks over ⌈P / ranks per host⌉ hosts, with S pieces (subdomains, or bodies
//! on the monolithic dual) of equal work, ⌈S/P⌉ on the busiest rank:
//! - decompose: [`DECOMPOSE_SECONDS_PER_DOF`] · n on every rank (not parallel);
//! - factorize: the plan's set-up time per piece · ⌈S/P⌉;
//! - coarse (TFETI): the dense factorization of GGᵀ, (6S)³/3 flops at [`DENSE_FLOPS`], after an
//!   allreduce of its (6S)² entries;
//! - products: nA · (the plan's solve time per piece · ⌈S/P⌉ + its per-row time · dual rows / P);
//! - reductions: nA · ([`DOTS_PER_PRODUCT`] allreduces of one number, one of the 6S-vector Gλ)
//!   and nA neighbour exchanges of the interface multipliers ([`NEIGHBOURS`] messages of
//!   2 · 8 · rows / P bytes; on several hosts the slower of the two links sets the time).
//!   An allreduce is ⌈log2 P⌉ steps of α + m/β (recursive doubling), the first
//!   ⌈log2 (ranks per host)⌉ through shared memory, the others through the network.
//!
//! Efficiency E(P) = T(1) / (P · T(P)).

use std::fmt::Write;
use std::path::Path;

use super::plan::Candidate;
use crate::error::{Error, Result};

/// Seconds per DOF of the decompose phase (METIS partition, subdomain meshes, rows of B), done
/// whole on every rank: fitted to run/results/cluster_verify.txt (0.043 s for the 12 456
/// subdomain DOFs of mesh.n = 12, 8 subdomains).
pub const DECOMPOSE_SECONDS_PER_DOF: f64 = 3.5e-6;
/// Flops per second of the coarse problem's dense Cholesky factorization (one core).
pub const DENSE_FLOPS: f64 = 1.0e9;
/// Allreduces of one number per A-product (the Krylov method's dot products).
pub const DOTS_PER_PRODUCT: f64 = 2.0;
/// Neighbour ranks a rank exchanges interface multipliers with (a 3-D partition).
pub const NEIGHBOURS: f64 = 6.0;
/// The rank counts of the forecast.
pub const RANKS: [usize; 13] = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096];

/// One kind of link: latency α and bandwidth β.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Link {
    /// Latency α of one message, in µs.
    pub latency_us: f64,
    /// Bandwidth β of one link, in GB/s.
    pub bandwidth_gb_s: f64,
}

impl Link {
    /// Seconds of one message of `bytes`: α + m/β.
    pub fn message(&self, bytes: f64) -> f64 {
        self.latency_us * 1e-6 + bytes / (self.bandwidth_gb_s * 1e9)
    }
}

/// The network model: the link between hosts and the shared memory inside one.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Network {
    /// The link between two hosts.
    pub network: Link,
    /// Two ranks on one host.
    pub shared_memory: Link,
}

impl Network {
    /// Reads the network model from a TOML file; errors name the file and the key.
    pub fn read(path: &Path) -> Result<Network> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display().to_string(), e))?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses the network model from TOML `text` of `file`.
    pub fn parse(text: &str, file: &str) -> Result<Network> {
        let bad = |msg: String| Error::Parse { file: file.into(), msg };
        let table: toml::Table = text.parse().map_err(|e: toml::de::Error| bad(e.message().trim().replace('\n', " ")))?;
        let net: Network = serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
            let key = e.path().to_string();
            bad(format!("{key}: {}", e.inner().message().trim().replace('\n', " ")))
        })?;
        for (key, v) in [
            ("network.latency_us", net.network.latency_us),
            ("network.bandwidth_gb_s", net.network.bandwidth_gb_s),
            ("shared_memory.latency_us", net.shared_memory.latency_us),
            ("shared_memory.bandwidth_gb_s", net.shared_memory.bandwidth_gb_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(format!("{key}: must be a positive number, got {v}")));
            }
        }
        Ok(net)
    }

    /// Seconds of an allreduce of `bytes` on `p` ranks, `per_host` of them on each host.
    pub fn allreduce(&self, p: usize, per_host: usize, bytes: f64) -> f64 {
        let steps = log2_ceil(p);
        let inside = log2_ceil(per_host.min(p)).min(steps);
        inside as f64 * self.shared_memory.message(bytes) + (steps - inside) as f64 * self.network.message(bytes)
    }
}

fn log2_ceil(p: usize) -> u32 {
    p.max(1).next_power_of_two().trailing_zeros()
}

/// The predicted seconds of one rank count.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Row {
    /// Ranks P.
    pub ranks: usize,
    /// Hosts ⌈P / ranks per host⌉.
    pub hosts: usize,
    /// Decompose.
    pub decompose: f64,
    /// Assembly to factors.
    pub factorize: f64,
    /// The coarse problem.
    pub coarse: f64,
    /// The A-products' local work.
    pub products: f64,
    /// The allreduces and neighbour exchanges of the iterations.
    pub reductions: f64,
    /// The sum.
    pub total: f64,
    /// E(P) = T(1) / (P · T(P)).
    pub efficiency: f64,
}

/// The forecast of candidate `c` (priced by the plan for `priced` ranks) of a mesh of `dofs`
/// DOFs, on every count of [`RANKS`] with `per_host` ranks per host.
pub fn forecast(c: &Candidate, priced: usize, dofs: usize, per_host: usize, net: &Network) -> Vec<Row> {
    let pieces: usize = c.parts.iter().sum::<usize>().max(1);
    let busy = |p: usize| pieces.div_ceil(p.max(1)) as f64;
    let rows = c.dual_rows() as f64;
    // the row rate that priced the candidate
    let row_rate = super::rates::current().rates.row;
    let factor_piece = c.t_factor / busy(priced);
    let solve_piece = (c.t_product - row_rate * rows / priced.max(1) as f64).max(0.0) / busy(priced);
    let coarse_dim = if c.tfeti { 6.0 * pieces as f64 } else { 0.0 };
    let interface = (c.gluing_rows + c.contact_rows) as f64;
    let mut out: Vec<Row> = RANKS
        .iter()
        .map(|&p| {
            let hosts = p.div_ceil(per_host.max(1));
            let pf = p as f64;
            let coarse = if c.tfeti { coarse_dim.powi(3) / 3.0 / DENSE_FLOPS + net.allreduce(p, per_host, 8.0 * coarse_dim * coarse_dim) } else { 0.0 };
            let exchange = if p == 1 {
                0.0
            } else {
                let bytes = 2.0 * 8.0 * interface / pf;
                let shm = NEIGHBOURS.min(pf - 1.0) * net.shared_memory.latency_us * 1e-6 + bytes / (net.shared_memory.bandwidth_gb_s * 1e9);
                let wire = NEIGHBOURS.min(pf - 1.0) * net.network.latency_us * 1e-6 + bytes / (net.network.bandwidth_gb_s * 1e9);
                if hosts > 1 {
                    shm.max(wire)
                } else {
                    shm
                }
            };
            let dots = DOTS_PER_PRODUCT * net.allreduce(p, per_host, 8.0) + if c.tfeti { net.allreduce(p, per_host, 8.0 * coarse_dim) } else { 0.0 };
            let mut r = Row {
                ranks: p,
                hosts,
                decompose: if c.tfeti { DECOMPOSE_SECONDS_PER_DOF * dofs as f64 } else { 0.0 },
                factorize: factor_piece * busy(p),
                coarse,
                products: c.n_a * (solve_piece * busy(p) + row_rate * rows / pf),
                reductions: c.n_a * (dots + exchange),
                ..Row::default()
            };
            r.total = r.decompose + r.factorize + r.coarse + r.products + r.reductions;
            r
        })
        .collect();
    let t1 = out[0].total;
    for r in &mut out {
        r.efficiency = t1 / (r.ranks as f64 * r.total);
    }
    out
}

/// The text `check --hosts` prints: the model, the network and one line per rank count.
pub fn table(c: &Candidate, priced: usize, dofs: usize, ranks: usize, hosts: usize, net: &Network, file: &str) -> String {
    let per_host = ranks.div_ceil(hosts.max(1));
    let mut s = format!(
        "scaling forecast of {} ({} ranks per host; network {file}: between hosts α = {} µs, β = {} GB/s; inside a host α = {} µs, β = {} GB/s):\n",
        c.label(),
        per_host,
        net.network.latency_us,
        net.network.bandwidth_gb_s,
        net.shared_memory.latency_us,
        net.shared_memory.bandwidth_gb_s
    );
    let _ = writeln!(
        s,
        "  {:>5} {:>5} {:>10} {:>10} {:>10} {:>10} {:>11} {:>10} {:>8} {:>6}",
        "ranks", "hosts", "decomp s", "factor s", "coarse s", "products s", "reductions s", "total s", "speed-up", "E %"
    );
    let rows = forecast(c, priced, dofs, per_host, net);
    let t1 = rows[0].total;
    for r in &rows {
        let _ = writeln!(
            s,
            "  {:>5} {:>5} {:>10.4} {:>10.4} {:>10.4} {:>10.4} {:>11.4} {:>10.4} {:>8.2} {:>6.1}",
            r.ranks,
            r.hosts,
            r.decompose,
            r.factorize,
            r.coarse,
            r.products,
            r.reductions,
            r.total,
            t1 / r.total,
            100.0 * r.efficiency
        );
    }
    let _ = writeln!(s, "  (the plan's cost model of this decomposition, its pieces spread evenly; allreduce: ⌈log2 P⌉ steps of α + m/β; docs/performance.md)");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn net() -> Network {
        Network::parse("[network]\nlatency_us = 1.0\nbandwidth_gb_s = 24.0\n[shared_memory]\nlatency_us = 0.5\nbandwidth_gb_s = 10.0\n", "n.toml").unwrap()
    }

    #[test]
    fn an_allreduce_is_log2_p_steps_inside_then_between_hosts() {
        let n = net();
        assert_eq!(n.allreduce(1, 4, 8.0), 0.0);
        // 8 ranks, 4 per host: 2 steps in shared memory, 1 over the network
        let want = 2.0 * (0.5e-6 + 8.0 / 10e9) + (1.0e-6 + 8.0 / 24e9);
        assert!((n.allreduce(8, 4, 8.0) - want).abs() < 1e-15);
        // 5 ranks: ⌈log2 5⌉ = 3 steps
        assert!((n.allreduce(5, 8, 0.0) - 3.0 * 0.5e-6).abs() < 1e-15);
    }

    #[test]
    fn a_malformed_network_names_the_key() {
        let e = Network::parse("[network]\nlatency_us = \"fast\"\nbandwidth_gb_s = 24.0\n[shared_memory]\nlatency_us = 0.5\nbandwidth_gb_s = 10.0\n", "n.toml")
            .unwrap_err();
        assert!(e.to_string().starts_with("n.toml: network.latency_us: "), "{e}");
        let e = Network::parse("[network]\nlatency_us = 1.0\nbandwidth_gb_s = -2.0\n[shared_memory]\nlatency_us = 0.5\nbandwidth_gb_s = 10.0\n", "n.toml")
            .unwrap_err();
        assert_eq!(e.to_string(), "n.toml: network.bandwidth_gb_s: must be a positive number, got -2");
        let e = Network::parse("[network]\nlatency_us = 1.0\nbandwith_gb_s = 2.0\n", "n.toml").unwrap_err();
        assert!(e.to_string().starts_with("n.toml: network.bandwith_gb_s: unknown field"), "{e}");
    }
}
