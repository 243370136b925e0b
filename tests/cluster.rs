//! The cluster paths: `run/cluster-verify` (single-node Slurm, ranks on several hosts in network
//! namespaces, the per-host memory check) run as root where its packages are installed, and the
//! docs' cluster section checked against the scripts it describes.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn on_path(cmd: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(cmd).is_file()))
}

fn is_root() -> bool {
    Command::new("id").arg("-u").output().is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

/// Every `run/…` path a text names, as written (trailing punctuation cut).
fn run_paths(text: &str) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for (i, _) in text.match_indices("run/") {
        if i > 0 && (text.as_bytes()[i - 1].is_ascii_alphanumeric() || text.as_bytes()[i - 1] == b'/') {
            continue; // a path that merely ends in run/ (e.g. /var/run/)
        }
        let p: String = text[i..].chars().take_while(|c| c.is_ascii_alphanumeric() || "/_.-".contains(*c)).collect();
        let p = p.trim_end_matches(['.', '/']).to_string();
        if p.len() > 4 && !v.contains(&p) {
            v.push(p);
        }
    }
    v
}

/// The cluster section of the docs names only scripts that exist, the commands it quotes are the
/// ones the scripts run, the variables it names are the ones run/scaling reads, and the image
/// leaves the transports to the site as it says.
#[test]
fn docs_cluster_section_matches_the_scripts() {
    let docs = read("docs/containers.md");
    let readme = read("README.md");
    let cluster_part = &readme[readme.find("On a cluster").expect("README: the cluster paragraph")..];
    for text in [docs.as_str(), cluster_part] {
        for p in run_paths(text) {
            let path = root().join(&p);
            assert!(path.exists(), "docs name {p}, which does not exist");
            if path.is_file() && !p.contains('.') {
                let mode = std::os::unix::fs::PermissionsExt::mode(&path.metadata().unwrap().permissions());
                assert!(mode & 0o111 != 0, "{p} is named as a script but is not executable");
            }
        }
    }
    // the checked commands, verbatim in the script that checks them
    let verify = read("run/cluster-verify");
    for cmd in [
        "sbatch --wait --ntasks=2",
        "run/scaling.slurm",
        "srun --mpi=pmix",
        "srun --mpi=list",
        "ch-convert",
        "unshare --uts",
        "btl_tcp_if_include",
        "oob_tcp_if_include",
        "mpirun --hostfile",
        "No route to host",
        "No such file or directory",
        "mpi/pmix",
    ] {
        assert!(docs.contains(cmd), "docs/containers.md no longer says `{cmd}`");
        assert!(verify.contains(cmd), "docs/containers.md says `{cmd}`, run/cluster-verify does not run it");
    }
    // the SCALING_* variables: the job script's header, the docs and run/scaling agree
    let slurm = read("run/scaling.slurm");
    let scaling = read("run/scaling");
    for text in [&slurm, &docs] {
        for (i, _) in text.match_indices("SCALING_") {
            let var: String = text[i..].chars().take_while(|c| c.is_ascii_uppercase() || *c == '_').collect();
            if var == "SCALING_" {
                continue; // "SCALING_*"
            }
            assert!(scaling.contains(&var), "{var} is named in the docs or run/scaling.slurm but run/scaling does not read it");
        }
    }
    assert!(slurm.contains("srun"), "run/scaling.slurm must launch its ranks with srun as the docs say");
    // "the image must not pin OMPI_MCA_btl": no OMPI_MCA_* in the image's ENV, only in its param file
    let dockerfile = read("Dockerfile");
    for line in dockerfile.lines().filter(|l| l.trim_start().starts_with("ENV")) {
        assert!(!line.contains("OMPI_MCA_"), "Dockerfile sets {line:?}: an image ENV overrides the host's OMPI_MCA_* (docs/containers.md)");
    }
    assert!(docs.contains("OMPI_ALLOW_RUN_AS_ROOT"), "docs/containers.md: the ENV it keeps");
    // the Apptainer definition builds from the image run/docker-verify makes
    let def = read("run/apptainer.def");
    assert!(def.contains("docker-archive"), "run/apptainer.def must build from the podman docker-archive");
}

/// `run/cluster-verify` end to end where it can run (its bad inputs included: an unreachable and
/// an unresolvable host in a hostfile, a Slurm job without PMIx): as root, with Slurm, munge, PMIx and
/// iproute2 installed (it installs nothing then) and the release binary built. Elsewhere the test
/// says why it did not run.
#[test]
fn cluster_verify_slurm_and_several_hosts() {
    let missing: Vec<&str> = ["slurmctld", "slurmd", "munged", "srun", "sbatch", "ip", "unshare", "mpirun"].into_iter().filter(|c| !on_path(c)).collect();
    let exe = root().join("target/release/tresca-feti");
    let why = if !is_root() {
        Some("not root".to_string())
    } else if !missing.is_empty() {
        Some(format!("missing {}", missing.join(", ")))
    } else if !exe.is_file() {
        Some(format!("{} not built", exe.display()))
    } else if !Path::new("/usr/include/pmix.h").exists() && !Path::new("/usr/lib/x86_64-linux-gnu/pmix2/include/pmix.h").exists() {
        Some("PMIx (libpmix-dev) not installed".to_string())
    } else {
        None
    };
    if let Some(why) = why {
        eprintln!("cluster_verify_slurm_and_several_hosts: not run ({why}); run/cluster-verify checks it as root");
        return;
    }
    let out = Command::new("timeout").args(["600", "run/cluster-verify"]).current_dir(root()).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "run/cluster-verify failed ({:?}):\n{}\n{}", out.status.code(), &stdout[stdout.len().saturating_sub(4000)..], stderr);
    let last = stdout.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("");
    assert!(last.starts_with("cluster-verify:"), "the summary line comes last: {last:?}");
    for part in [
        "slurm ok",
        "srun --mpi=pmix -n 2 u bitwise",
        "2 hosts x1 ok",
        "2 hosts x2 ok",
        "3 hosts x1 ok",
        "memory per host ok",
        "bad inputs one line each (unreachable host, unresolved host, slurm without pmix)",
    ] {
        assert!(last.contains(part), "summary lacks {part:?}: {last}");
    }
    // the bad inputs' lines as the script printed them: the cause named, not a banner
    for part in [
        "2 hosts x 1 rank: solved",
        "bitwise equal",
        "hostfile, unreachable host (exit 1): error: case n4_s2_oblique_p2: the launcher failed",
        "No route to host",
        "Could not resolve hostname h8",
        "Couldn't find the specified plugin name for mpi/pmix",
    ] {
        assert!(stdout.contains(part) || stderr.contains(part), "cluster-verify's log lacks {part:?}");
    }
}
