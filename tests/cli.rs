//! The command line as a user meets it: `check`, `solve`, bad input (one line on stderr naming
//! the key or file, exit code ≠ 0, no panic, no result file), and runs under `mpirun` with 1, 2
//! and 3 ranks giving identical fields.

mod common;

use std::path::Path;

use common::{assert_clean_failure, fields, mpirun, mpirun_cmd, root, run, tmpdir};
use tresca_feti::output::{OutputData, Values};

const SEED: &str = include_str!("../run/seed.toml");

fn seed_with(from: &str, to: &str) -> String {
    assert!(SEED.contains(from), "seed.toml has no `{from}`");
    SEED.replacen(from, to, 1)
}

fn abs_mesh(rel: &str) -> String {
    root().join("mesh").join(rel).display().to_string()
}

#[test]
fn bad_input_gives_one_line_and_no_file() {
    let off = ["--set", "contact.enabled=false"];
    assert_clean_failure("malformed", &seed_with("[mesh]", "[mesh"), &[], &["scene.toml", "line 7"]);
    assert_clean_failure("unknown-key", &seed_with("eps = 1e-8", "epsilon = 1e-8"), &[], &["solver", "epsilon"]);
    assert_clean_failure("unknown-key-set", SEED, &["--set", "mesh.nn=3"], &["mesh", "nn"]);
    assert_clean_failure("nu", &seed_with("nu = 0.35", "nu = 0.5"), &off, &["material[1].nu", "0.5"]);
    assert_clean_failure("E", &seed_with("E = 50000.0", "E = 0.0"), &off, &["material[0].E"]);
    assert_clean_failure("E-negative", &seed_with("E = 50000.0", "E = -1.0"), &off, &["material[0].E"]);
    assert_clean_failure("N", SEED, &["--set", "mesh.n=1"], &["mesh.n", "at least 2"]);
    assert_clean_failure("N-negative", SEED, &["--set", "mesh.n=-4"], &["mesh.n"]);
    assert_clean_failure("face", &seed_with("face = \"upper.zmax\"", "face = \"upper.top\""), &off, &["traction[0].face", "upper.top"]);
    assert_clean_failure("slave", &seed_with("slave = \"upper.zmin\"", "slave = \"upper.bottom\""), &off, &["contact.pair[0].slave", "upper.bottom"]);
    assert_clean_failure("nan-load", &seed_with("p = [0.0, 0.0, -1.0]", "p = [0.0, nan, -1.0]"), &off, &["traction[0].p", "finite"]);
    assert_clean_failure("inf-coord", &seed_with("max = [2.0, 1.0, 2.0]", "max = [2.0, inf, 2.0]"), &off, &["body[0].box.max", "finite"]);
    assert_clean_failure("zero-subdomains", SEED, &["--set", "decomposition.subdomains=0"], &["decomposition.subdomains"]);
    assert_clean_failure(
        "both-subdomains-and-target",
        SEED,
        &["--set", "decomposition.subdomains=2", "--set", "decomposition.target_dofs=1000"],
        &["decomposition.target_dofs", "not both"],
    );
    assert_clean_failure("bad-penalty", SEED, &["--set", "decomposition.penalty=-1"], &["decomposition.penalty"]);
    assert_clean_failure("bad-clusters", SEED, &["--set", "decomposition.subdomains_per_cluster=0"], &["decomposition.subdomains_per_cluster"]);
    // a cluster whose dense corner problem would be too large: refused before any factorization
    assert_clean_failure(
        "huge-cluster",
        SEED,
        &["--set", "mesh.n=16", "--set", "decomposition.subdomains=512", "--set", "decomposition.subdomains_per_cluster=512"],
        &["decomposition.subdomains_per_cluster", "smaller clusters"],
    );
    assert_clean_failure("bad-coarse-solve", SEED, &["--set", "decomposition.coarse_solve=\"fast\""], &["decomposition.coarse_solve", "explicit"]);
    assert_clean_failure("bad-projector", SEED, &["--set", "decomposition.projector=\"skew\""], &["decomposition.projector"]);
    assert_clean_failure(
        "too-many-subdomains",
        SEED,
        &["--set", "decomposition.subdomains=100000", "--set", "mesh.n=4"],
        &["decomposition.subdomains", "exceed"],
    );
    assert_clean_failure("bad-set", SEED, &["--set", "mesh.n"], &["--set mesh.n", "key=value"]);
    assert_clean_failure("floating", &seed_with("face = \"lower.xmin\"", "face = \"upper.xmin\""), &off, &["lower", "floats"]);
    assert_clean_failure(
        "rollers-only",
        SEED,
        &["--set", "dirichlet.0.components=[\"z\"]", "--set", "contact.enabled=false"],
        &["dirichlet", "body \"upper\"", "translation along x", "rotation about z", "rotation about an axis along y", "held by no Dirichlet condition"],
    );
    assert_clean_failure(
        "held-by-nothing",
        SEED,
        &["--set", "dirichlet.0.face=\"lower.xmin\"", "--set", "contact.pair.0.friction={type=\"none\"}"],
        &["dirichlet", "body \"upper\"", "translation along x", "translation along y", "rotation about z", "neither Dirichlet conditions nor contact"],
    );
    assert_clean_failure(
        "load-factors",
        SEED,
        &["--set", "load.steps=2", "--set", "traction.1.factors=[1.0]"],
        &["traction[1].factors", "one factor per load step"],
    );
    assert_clean_failure("load-steps", SEED, &["--set", "load.steps=0"], &["load.steps"]);
    assert_clean_failure("bad-friction", &seed_with("type = \"tresca\"", "type = \"glue\""), &off, &["friction", "glue"]);
    assert_clean_failure("bad-field", SEED, &["--set", "output.fields=[\"stress\"]"], &["output.fields[0]", "stress"]);
    // meshes
    let gmsh_body = |file: &str| seed_with("box = { min = [0.0, 0.0, 0.0], max = [2.0, 1.0, 1.0] }", &format!("gmsh = {{ file = \"{file}\" }}"));
    assert_clean_failure("missing-mesh", &gmsh_body("/nonexistent/blocks.msh"), &off, &["/nonexistent/blocks.msh"]);
    // a tetrahedral mesh is read: what fails is the scene's face on it (tet.msh names `top` only)
    assert_clean_failure("tet-mesh", &gmsh_body(&abs_mesh("tet.msh")), &off, &["dirichlet[1].face", "unknown face \"lower.xmin\"", "lower.top"]);
    let dir = tmpdir("truncated-mesh");
    let full = std::fs::read_to_string(root().join("mesh/two_blocks.msh")).unwrap();
    let cut = dir.join("cut.msh");
    std::fs::write(&cut, &full[..full.len() / 2]).unwrap();
    assert_clean_failure("truncated-mesh", &gmsh_body(cut.to_str().unwrap()), &off, &["cut.msh"]);
    // an unknown solver, and solver settings out of range
    assert_clean_failure("method", SEED, &["--set", "mesh.n=3", "--set", "solver.method=\"cg\""], &["solver.method", "cg"]);
    assert_clean_failure("inner-tol", SEED, &["--set", "mesh.n=3", "--set", "solver.inner_tol=2.0"], &["solver.inner_tol"]);
    assert_clean_failure("cg-stop", SEED, &["--set", "mesh.n=3", "--set", "solver.cg_stop=\"never\""], &["solver.cg_stop"]);
    // a key the method does not read, and a preconditioner where none applies (one place decides)
    assert_clean_failure(
        "key-of-another-method",
        SEED,
        &["--set", "mesh.n=3", "--set", "solver.method=\"gimssn\"", "--set", "solver.forcing=2"],
        &["solver.forcing", "not a setting of method \"gimssn\""],
    );
    assert_clean_failure(
        "mssn-reads-no-rtol",
        SEED,
        &["--set", "mesh.n=3", "--set", "solver.method=\"mssn\"", "--set", "solver.rtol=0.3"],
        &["solver.rtol", "mssn"],
    );
    assert_clean_failure(
        "preconditioner-monolithic",
        SEED,
        &["--set", "mesh.n=3", "--set", "solver.method=\"tssn\"", "--set", "solver.preconditioner=\"dirichlet\""],
        &["solver.preconditioner", "monolithic"],
    );
    assert_clean_failure(
        "preconditioner-imssn",
        SEED,
        &["--set", "mesh.n=3", "--set", "solver.method=\"imssn\"", "--set", "solver.preconditioner=\"lumped\"", "--set", "decomposition.subdomains=2"],
        &["solver.preconditioner", "\"imssn\" takes none"],
    );
    assert_clean_failure(
        "preconditioner-orthogonal",
        SEED,
        &[
            "--set",
            "mesh.n=3",
            "--set",
            "solver.method=\"mssn\"",
            "--set",
            "solver.preconditioner=\"lumped\"",
            "--set",
            "decomposition.subdomains=2",
            "--set",
            "decomposition.projector=\"orthogonal\"",
        ],
        &["solver.preconditioner", "\"mssn\" takes none"],
    );
    assert_clean_failure(
        "preconditioner-unprojected",
        SEED,
        &[
            "--set",
            "mesh.n=3",
            "--set",
            "solver.method=\"tssn\"",
            "--set",
            "solver.preconditioner=\"lumped\"",
            "--set",
            "decomposition.subdomains=2",
            "--set",
            "decomposition.projected_cg=false",
        ],
        &["solver.preconditioner", "projected_cg"],
    );
    assert_clean_failure("tssn-patience", SEED, &["--set", "mesh.n=3", "--set", "solver.method=\"tssn\"", "--set", "solver.patience=-1"], &["solver.patience"]);
    assert_clean_failure(
        "coulomb-mixed",
        SEED,
        &["--set", "mesh.n=3", "--set", "contact.pair.0.friction={type=\"coulomb\", mu=0.3, mu1=0.2}"],
        &["contact.pair[0].friction", "mu1"],
    );
    assert_clean_failure(
        "coulomb-negative",
        SEED,
        &["--set", "mesh.n=3", "--set", "contact.pair.0.friction={type=\"coulomb\", mu=-1.0}"],
        &["contact.pair[0].friction.mu"],
    );
    assert_clean_failure("export-tresca", SEED, &["--set", "mesh.n=3", "--set", "output.export_dual=\"x.h5\""], &["output.export_dual", "Coulomb"]);
    assert_clean_failure(
        "export-tfeti",
        SEED,
        &[
            "--set",
            "mesh.n=3",
            "--set",
            "decomposition.subdomains=2",
            "--set",
            "contact.pair.0.friction={type=\"coulomb\", mu=0.3}",
            "--set",
            "output.export_dual=\"x.h5\"",
        ],
        &["output.export_dual", "TFETI"],
    );
    assert_clean_failure(
        "cylinder-side",
        SEED,
        &["--set", "mesh.n=3", "--set", "body.0.box.cylinder={side=\"ymin\", radius=4.0}"],
        &["body[0].box.cylinder.side", "zmin", "zmax"],
    );
    assert_clean_failure(
        "cylinder-radius",
        SEED,
        &["--set", "mesh.n=3", "--set", "body.0.box.cylinder={side=\"zmin\", radius=0.5}"],
        &["body[0].box.cylinder.radius"],
    );
    assert_clean_failure(
        "coulomb-empty",
        SEED,
        &["--set", "mesh.n=3", "--set", "contact.pair.0.friction={type=\"coulomb\"}"],
        &["contact.pair[0].friction", "mu"],
    );
    assert_clean_failure("auto-own-key", SEED, &["--set", "mesh.n=3", "--set", "solver.rtol=0.3"], &["solver.rtol", "solver.method"]);
    // a solver that cannot reach ε within its iterations says so
    assert_clean_failure(
        "no-convergence",
        SEED,
        &["--set", "mesh.n=4", "--set", "solver.max_outer=2", "--set", "solver.eps=1e-12"],
        &["TSSN", "no convergence"],
    );
}

const GMSH: &str = include_str!("../run/gmsh_blocks.toml");

/// The Gmsh scene (`run/gmsh_blocks.toml`) reading both bodies from `mesh` instead.
fn gmsh_scene(mesh: &Path) -> String {
    assert!(GMSH.contains("\"../mesh/two_blocks.msh\""));
    GMSH.replace("\"../mesh/two_blocks.msh\"", &format!("\"{}\"", mesh.display()))
}

/// `mesh/two_blocks.msh` with `from` replaced by `to` (exactly once).
fn msh_with(from: &str, to: &str) -> String {
    let full = std::fs::read_to_string(root().join("mesh/two_blocks.msh")).unwrap();
    assert_eq!(full.matches(from).count(), 1, "two_blocks.msh: `{from}` is not unique");
    full.replacen(from, to, 1)
}

/// A seed scene with `extra` appended (more `[[face]]`, `[[contact.pair]]` entries, …).
fn seed_plus(extra: &str) -> String {
    format!("{SEED}\n{extra}")
}

/// Bad-input cases collected first and then checked four at a time (each run is mostly the
/// start-up of MPI, waiting rather than computing).
#[derive(Default)]
struct Failures(Vec<(String, String, Vec<String>, Vec<String>)>);

impl Failures {
    fn add(&mut self, name: &str, scene: &str, extra: &[&str], expect: &[&str]) {
        assert!(self.0.iter().all(|c| c.0 != name), "case name {name} used twice");
        let owned = |v: &[&str]| v.iter().map(|s| s.to_string()).collect();
        self.0.push((name.into(), scene.into(), owned(extra), owned(expect)));
    }

    fn check(self) {
        let next = std::sync::atomic::AtomicUsize::new(0);
        std::thread::scope(|scope| {
            for _ in 0..4 {
                scope.spawn(|| {
                    while let Some((name, scene, extra, expect)) = self.0.get(next.fetch_add(1, std::sync::atomic::Ordering::Relaxed)) {
                        let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
                        let expect: Vec<&str> = expect.iter().map(String::as_str).collect();
                        assert_clean_failure(name, scene, &extra, &expect);
                    }
                });
            }
        });
    }
}

/// Malformed scenes and meshes beyond `bad_input_gives_one_line_and_no_file`: duplicate names,
/// contact faces that do not meet, NaN/inf anywhere, broken `.msh` files, sizes out of range.
/// Each must fail with exit code 1, one line naming the key or file, and no output file.
#[test]
fn malformed_meshes_and_geometry_give_one_line_and_no_file() {
    let mut bad = Failures::default();
    let off = ["--set", "mesh.n=3", "--set", "contact.enabled=false"];
    let n4 = ["--set", "mesh.n=4"];
    let face = |name: &str, body: &str, from: &str| {
        format!("[[face]]\nname = \"{name}\"\nbody = \"{body}\"\nfrom = \"{from}\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 2.0]\n")
    };

    // duplicate names
    let twice = face("patch", "upper", "zmax") + &face("patch", "upper", "zmax");
    bad.add("dup-face", &seed_plus(&twice), &off, &["face[1].name", "upper.patch", "already exists"]);
    bad.add("face-like-box-face", &seed_plus(&face("zmin", "upper", "zmax")), &off, &["face[0].name", "upper.zmin", "already exists"]);
    bad.add("face-unknown-body", &seed_plus(&face("patch", "middle", "zmax")), &off, &["face[0].body", "middle"]);
    bad.add("face-unknown-from", &seed_plus(&face("patch", "upper", "top")), &off, &["face[0].from", "upper.top"]);
    let empty =
        face("patch", "upper", "zmax").replace("min = [0.0, 0.0, 0.0]", "min = [5.0, 0.0, 0.0]").replace("max = [1.0, 1.0, 2.0]", "max = [6.0, 1.0, 2.0]");
    bad.add("face-empty-box", &seed_plus(&empty), &off, &["face[0]", "upper.zmax", "no facet", "the box"]);
    let lower_body = "[[body]]\nname = \"lower\"\nmaterial = \"lower\"";
    let dup_body = seed_with(lower_body, "[[body]]\nname = \"upper\"\nmaterial = \"lower\"");
    bad.add("dup-body", &dup_body, &off, &["body[1].name", "duplicate body name \"upper\""]);
    let dup_mat = seed_with("name = \"lower\"\nE = 50000.0", "name = \"upper\"\nE = 50000.0");
    bad.add("dup-material", &dup_mat, &off, &["material[1].name", "duplicate material name \"upper\""]);

    // contact faces that do not meet, or do not match node to node
    let pair = |slave: &str, master: &str| seed_with("slave = \"upper.zmin\"\nmaster = \"lower.zmax\"", &format!("slave = \"{slave}\"\nmaster = \"{master}\""));
    bad.add("pair-zmin-xmin", &pair("upper.zmin", "lower.xmin"), &n4, &["contact.pair[0]", "upper.zmin", "lower.xmin", "do not face each other"]);
    bad.add("pair-zmax-zmax", &pair("upper.zmax", "lower.zmax"), &n4, &["contact.pair[0]", "upper.zmax", "lower.zmax", "do not face each other"]);
    bad.add("pair-zmin-zmin", &pair("upper.zmin", "lower.zmin"), &n4, &["contact.pair[0]", "do not face each other"]);
    // opposite normals but the master lies behind the slave: no slave node finds a master facet
    // in front (mortar, the default where the nodes do not match): an error naming both faces
    bad.add(
        "pair-xmin-xmax",
        &pair("upper.xmin", "lower.xmax"),
        &n4,
        &["contact.pair[0]", "upper.xmin", "lower.xmax", "no slave node", "finds a master facet"],
    );
    bad.add("pair-same-body", &pair("upper.zmin", "upper.zmax"), &n4, &["contact.pair[0]", "same body"]);
    bad.add("pair-unknown-body", &pair("upper.zmin", "ground.zmax"), &n4, &["contact.pair[0].master", "ground.zmax"]);
    // non-matching faces refused where node-to-node is asked for (mortar takes them)
    let n2n = |scene: String| scene.replacen("master = \"lower.zmax\"", "master = \"lower.zmax\"\ndiscretization = \"node-to-node\"", 1);
    let lower_box = "box = { min = [0.0, 0.0, 0.0], max = [2.0, 1.0, 1.0] }";
    let upper_box = "box = { min = [0.0, 0.0, 1.0], max = [2.0, 1.0, 2.0] }";
    let more_nodes = seed_with(lower_box, "box = { min = [0.0, 0.0, 0.0], max = [2.0, 1.0, 1.0], nodes = [5, 4, 4] }");
    bad.add("pair-node-count", &n2n(more_nodes), &n4, &["contact.pair[0]", "16 nodes", "20", "node-to-node"]);
    // the same node count (5 × 4) on both faces, but in other places
    let crossed = seed_with(lower_box, "box = { min = [0.0, 0.0, 0.0], max = [2.0, 1.0, 1.0], nodes = [4, 5, 4] }").replacen(
        upper_box,
        "box = { min = [0.0, 0.0, 1.0], max = [2.0, 1.0, 2.0], nodes = [5, 4, 4] }",
        1,
    );
    bad.add("pair-crossed-grids", &n2n(crossed), &n4, &["contact.pair[0]", "do not match node to node"]);
    // shifted sideways by half an element (h = 2/3 at N = 4)
    let shifted = seed_with(upper_box, "box = { min = [0.3333333333333333, 0.0, 1.0], max = [2.3333333333333333, 1.0, 2.0] }");
    bad.add("pair-half-shift", &n2n(shifted), &n4, &["contact.pair[0]", "do not match node to node", "0.333333"]);
    let overlap = seed_with(upper_box, "box = { min = [0.0, 0.0, 0.9], max = [2.0, 1.0, 2.0] }");
    bad.add("overlap", &overlap, &n4, &["contact.pair[0]", "bodies overlap", "1.000e-1"]);
    // the same interface twice, or once from each side: doubled constraints and friction
    let entry = "[[contact.pair]]\nslave = \"upper.zmin\"\nmaster = \"lower.zmax\"\nfriction = { type = \"tresca\", g = 0.09 }\n";
    bad.add("pair-twice", &seed_plus(entry), &n4, &["contact.pair[1]", "already a pair of contact.pair[0]"]);
    let swapped = entry.replace("upper.zmin", "X").replace("lower.zmax", "upper.zmin").replace("X", "lower.zmax");
    bad.add("pair-swapped", &seed_plus(&swapped), &n4, &["contact.pair[1]", "lower.zmax", "already a pair of contact.pair[0]"]);

    // NaN and inf anywhere
    for (name, set, key) in [
        ("nan-E", "material.0.E=nan", "material[0].E"),
        ("inf-E", "material.1.E=inf", "material[1].E"),
        ("nan-nu", "material.0.nu=nan", "material[0].nu"),
        ("nan-g", "contact.pair.0.friction.g=nan", "contact.pair[0].friction.g"),
        ("inf-g", "contact.pair.0.friction.g=inf", "contact.pair[0].friction.g"),
        ("inf-traction", "traction.1.p=[0.0, -inf, 0.0]", "traction[1].p"),
        ("nan-dirichlet", "dirichlet.0.value=[0.0, nan, 0.0]", "dirichlet[0].value"),
        ("inf-dirichlet", "dirichlet.1.value=[inf, 0.0, 0.0]", "dirichlet[1].value"),
        ("nan-box-min", "body.1.box.min=[nan, 0.0, 0.0]", "body[1].box.min"),
        ("inf-box-max", "body.1.box.max=[2.0, 1.0, -inf]", "body[1].box.max"),
        ("nan-eps", "solver.eps=nan", "solver.eps"),
        ("inf-eps", "solver.eps=inf", "solver.eps"),
        ("nan-rho", "solver.rho_factor=nan", "solver.rho_factor"),
        ("inf-rho", "solver.rho_factor=inf", "solver.rho_factor"),
        ("nan-gamma", "solver.gamma=nan", "solver.gamma"),
        ("nan-rtol", "solver.rtol=nan", "solver.rtol"),
        ("nan-tolerance", "contact.pair.0.tolerance=nan", "contact.pair[0].tolerance"),
        ("nan-penalty", "decomposition.penalty=nan", "decomposition.penalty"),
        ("nan-g2", "contact.pair.0.friction={type=\"orthotropic\", g1=0.09, g2=nan, direction=[1.0, 0.0, 0.0]}", "contact.pair[0].friction.g2"),
        ("inf-direction", "contact.pair.0.friction={type=\"orthotropic\", g1=0.09, g2=0.03, direction=[inf, 0.0, 0.0]}", "contact.pair[0].friction.direction"),
    ] {
        bad.add(name, SEED, &["--set", "mesh.n=3", "--set", set], &[key]);
    }
    let nan_face = face("patch", "upper", "zmax").replace("min = [0.0, 0.0, 0.0]", "min = [0.0, nan, 0.0]");
    bad.add("nan-face-min", &seed_plus(&nan_face), &off, &["face[0].min", "finite"]);
    // finite ends whose difference is not
    bad.add(
        "box-overflow",
        SEED,
        &["--set", "mesh.n=3", "--set", "body.1.box.min=[-1e308, 0.0, 0.0]", "--set", "body.1.box.max=[1e308, 1.0, 1.0]"],
        &["body[1].box", "overflows"],
    );
    let dir = tmpdir("bad-meshes");
    let inf_translate = gmsh_scene(&root().join("mesh/two_blocks.msh")).replacen("volume = \"upper\"", "volume = \"upper\", translate = [0.0, inf, 0.0]", 1);
    bad.add("inf-translate", &inf_translate, &[], &["body[0].gmsh.translate", "finite"]);

    // sizes and solver settings out of range
    bad.add("N-zero", SEED, &["--set", "mesh.n=0"], &["mesh.n", "at least 2"]);
    bad.add("N-huge", SEED, &["--set", "mesh.n=100000"], &["mesh.n", "upper", "at most"]);
    bad.add("box-nodes-huge", SEED, &["--set", "body.0.box.nodes=[3, 3, 1000000000]"], &["body[0].box.nodes", "at most"]);
    bad.add("box-nodes-one", SEED, &["--set", "body.0.box.nodes=[1, 3, 3]"], &["body[0].box.nodes", "at least 2"]);
    bad.add("box-nodes-negative", SEED, &["--set", "body.0.box.nodes=[3, -3, 3]"], &["body[0].box.nodes[1]", "-3"]);
    bad.add("subdomains-negative", SEED, &["--set", "decomposition.subdomains=-2"], &["decomposition.subdomains", "-2"]);
    bad.add("target-dofs-zero", SEED, &["--set", "decomposition.target_dofs=0"], &["decomposition.target_dofs", "at least 24"]);
    bad.add(
        "subdomains-exceed-n6",
        SEED,
        &["--set", "mesh.n=6", "--set", "decomposition.subdomains=126"],
        &["decomposition.subdomains", "126", "125 elements"],
    );
    // as many subdomains as elements: METIS leaves a part empty
    bad.add("subdomains-empty-part", SEED, &["--set", "mesh.n=6", "--set", "decomposition.subdomains=125"], &["upper", "empty", "fewer subdomains"]);
    for (name, set, key) in [
        ("eps-negative", "solver.eps=-1e-6", "solver.eps"),
        ("eps-zero", "solver.eps=0.0", "solver.eps"),
        ("rho-zero", "solver.rho_factor=0.0", "solver.rho_factor"),
        ("max-outer-zero", "solver.max_outer=0", "solver.max_outer"),
        ("max-inner-zero", "solver.max_inner=0", "solver.max_inner"),
        ("power-zero", "solver.power_iterations=0", "solver.power_iterations"),
        ("g-negative", "contact.pair.0.friction.g=-0.09", "contact.pair[0].friction.g"),
        ("g1-negative", "contact.pair.0.friction={type=\"orthotropic\", g1=-0.09, g2=0.03, direction=[1.0, 0.0, 0.0]}", "contact.pair[0].friction.g1"),
        ("direction-zero", "contact.pair.0.friction={type=\"orthotropic\", g1=0.09, g2=0.03, direction=[0.0, 0.0, 0.0]}", "contact.pair[0].friction.direction"),
        (
            "direction-normal",
            "contact.pair.0.friction={type=\"orthotropic\", g1=0.09, g2=0.03, direction=[0.0, 0.0, 1.0]}",
            "contact.pair[0].friction.direction",
        ),
        ("tolerance-negative", "contact.pair.0.tolerance=-1.0", "contact.pair[0].tolerance"),
        ("dirichlet-missing-face", "dirichlet.0.face=\"upper.nope\"", "dirichlet[0].face"),
        ("dirichlet-no-components", "dirichlet.0.components=[]", "dirichlet[0].components"),
        ("traction-unknown-body", "traction.0.face=\"middle.zmax\"", "traction[0].face"),
        ("traction-no-body", "traction.0.face=\"zmax\"", "traction[0].face"),
        ("unknown-material", "body.0.material=\"steel\"", "body[0].material"),
    ] {
        bad.add(name, SEED, &["--set", "mesh.n=3", "--set", set], &[key]);
    }
    bad.add(
        "direction-normal-named",
        SEED,
        &["--set", "mesh.n=3", "--set", "contact.pair.0.friction={type=\"orthotropic\", g1=0.09, g2=0.03, direction=[0.0, 0.0, 1.0]}"],
        &["normal to the contact face upper.zmin"],
    );

    // .msh files
    let full = std::fs::read_to_string(root().join("mesh/two_blocks.msh")).unwrap();
    let lines: Vec<&str> = full.lines().collect();
    let first = |n: usize| lines[..n].iter().map(|l| format!("{l}\n")).collect::<String>();
    let without = |line: &str| {
        assert_eq!(lines.iter().filter(|l| **l == line).count(), 1, "{line}");
        lines.iter().filter(|l| **l != line).map(|l| format!("{l}\n")).collect::<String>()
    };
    let noise: String = (0..4000u32).map(|i| char::from(b' ' + ((i.wrapping_mul(2654435761) >> 13) % 94) as u8)).collect();
    let meshes: Vec<(&str, String, Vec<&str>)> = vec![
        ("header-only.msh", first(3), vec!["no $Nodes section"]),
        ("no-elements.msh", first(576), vec!["no $Elements section"]),
        ("mid-nodes.msh", first(150), vec!["not a readable Gmsh 4.1 mesh", "node section"]),
        ("mid-elements.msh", first(700), vec!["not a readable Gmsh 4.1 mesh", "element section"]),
        ("no-end-elements.msh", first(lines.len() - 1), vec!["expected $EndElements"]),
        ("empty.msh", String::new(), vec!["does not start with $MeshFormat"]),
        ("text.msh", "Lorem ipsum dolor sit amet\nconsectetur adipiscing elit\n".into(), vec!["does not start with $MeshFormat"]),
        ("noise.msh", noise, vec!["does not start with $MeshFormat"]),
        ("no-end-nodes.msh", without("$EndNodes"), vec!["expected $EndNodes", "$Nodes section", "line 576"]),
        ("no-end-entities.msh", without("$EndEntities"), vec!["expected $EndEntities"]),
        ("no-end-names.msh", without("$EndPhysicalNames"), vec!["expected $EndPhysicalNames"]),
        ("unknown-type.msh", msh_with("\n3 2 5 54\n", "\n3 2 1000 54\n"), vec!["unknown element type", "value 1000", "line 721"]),
        (
            "hex-undefined-node.msh",
            msh_with("189 88 184 224 164 15 64 144 66 ", "189 88 184 224 164 15 64 144 999 "),
            vec!["hexahedron 189", "node 999", "not in $Nodes"],
        ),
        ("quad-undefined-node.msh", msh_with("\n2 23 89 90 24 \n", "\n2 23 89 90 999 \n"), vec!["quadrangle 2", "node 999", "not in $Nodes"]),
        ("dup-node.msh", msh_with("0 2 0 1\n2\n0 0 1\n", "0 2 0 1\n1\n0 0 1\n"), vec!["node 1 is defined twice"]),
        ("nan-node.msh", msh_with("0 2 0 1\n2\n0 0 1\n", "0 2 0 1\n2\n0 nan 1\n"), vec!["node 2", "non-finite coordinate", "NaN"]),
        ("inf-node.msh", msh_with("0 2 0 1\n2\n0 0 1\n", "0 2 0 1\n2\n0 0 1e400\n"), vec!["node 2", "non-finite coordinate", "inf"]),
        ("twisted.msh", msh_with("189 88 184 224 164 15 64 144 66 ", "189 184 88 224 164 15 64 144 66 "), vec!["hexahedron 189", "twisted"]),
        ("v22.msh", msh_with("4.1 0 8\n", "2.2 0 8\n"), vec!["format version 2.2", "msh41"]),
        ("v40.msh", msh_with("4.1 0 8\n", "4.0 0 8\n"), vec!["format version 4.0"]),
        ("binary-flag.msh", msh_with("4.1 0 8\n", "4.1 1 8\n"), vec!["binary", "line 3"]),
    ];
    for (file, text, expect) in &meshes {
        let path = dir.join(file);
        std::fs::write(&path, text).unwrap();
        let mut e = vec![*file];
        e.extend(expect);
        bad.add(file, &gmsh_scene(&path), &[], &e);
    }
    let ok = dir.join("ok.msh");
    std::fs::write(&ok, &full).unwrap();
    bad.add(
        "no-volume",
        &gmsh_scene(&ok).replacen("volume = \"upper\"", "volume = \"nope\"", 1),
        &[],
        &["ok.msh", "no physical volume named \"nope\"", "\"upper\", \"lower\""],
    );
    let tet = gmsh_scene(&root().join("mesh/tet.msh")).replacen("volume = \"upper\"", "volume = \"body\"", 1);
    // the upper body, physical volume "body" of tetrahedra, is read; the lower one is not there
    bad.add("tet-volume", &tet, &[], &["tet.msh", "no physical volume named \"lower\"", "(known: \"body\")"]);
    bad.check();
}

/// Tetrahedral Gmsh meshes are read and solved: the Gmsh scene on the two blocks meshed with
/// 4-node and with 10-node tetrahedra (mesh/make_fixtures.py), contact included; the result
/// file holds the cells as read, and the XDMF sidecar their topology. The answers against the
/// seed scene (the same geometry, materials and loads) on 16 × 16 × 16 hexahedral nodes per
/// block: the contact force and max |u| within about 2× of what was measured 2026-12-05 (tet4:
/// F_z −1.2 %, max |u| −24 %, the stiff linear tetrahedra of a coarse mesh; tet10: −0.11 %,
/// −2.1 %).
#[test]
fn tetrahedral_gmsh_meshes_are_read_and_solved() {
    let dir = tmpdir("tet-gmsh");
    let reference = common::solve(&root().join("run/seed.toml"), &["mesh.n=16"], &dir.join("seed16.h5"));
    let (ref_f, ref_u) = (reference.report.contact.as_ref().unwrap().total_force_on_slave[2], reference.report.results.max_displacement);
    for (file, kind, cells, topology, tol_f, tol_u) in [
        ("two_tet_blocks.msh", tresca_feti::mesh::CellKind::Tet4, 532, "Tetrahedron", 0.025, 0.35),
        ("two_tet10_blocks.msh", tresca_feti::mesh::CellKind::Tet10, 289, "Tetrahedron_10", 0.003, 0.04),
    ] {
        let scene = dir.join(format!("{file}.toml"));
        std::fs::write(&scene, gmsh_scene(&root().join("mesh").join(file))).unwrap();
        let out = dir.join(format!("{file}.h5"));
        let o = run(&["solve", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--quiet"]);
        assert!(o.status.success(), "{file}: {}", String::from_utf8_lossy(&o.stderr));
        let data = fields(&out);
        assert_eq!(data.cells.len(), cells, "{file}");
        assert!(data.cells.iter().all(|c| c.kind == kind), "{file}");
        let xdmf = std::fs::read_to_string(out.with_extension("xdmf")).unwrap();
        assert!(xdmf.contains(&format!("<Topology TopologyType=\"{topology}\" NumberOfElements=\"{cells}\">")), "{xdmf}");
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap()).unwrap();
        let fz = report["contact"]["total_force_on_slave"][2].as_f64().unwrap();
        let umax = report["results"]["max_displacement"].as_f64().unwrap();
        eprintln!(
            "{file}: F_z {fz:.5} against {ref_f:.5} ({:+.2} %), max |u| {umax:.4e} against {ref_u:.4e} ({:+.1} %)",
            100.0 * (fz / ref_f - 1.0),
            100.0 * (umax / ref_u - 1.0)
        );
        assert!((fz / ref_f - 1.0).abs() <= tol_f, "{file}: contact force {fz} against {ref_f}");
        assert!((umax / ref_u - 1.0).abs() <= tol_u, "{file}: max |u| {umax:e} against {ref_u:e}");
    }
}

/// Degenerate friction data that is allowed: an orthotropic bound of zero along one axis (the
/// ellipse is a segment) and a direction whose squared length overflows or underflows — the
/// latter two give the u of the direction [1, 0, 1] (to 1e-12), the first a u of its own.
#[test]
fn degenerate_but_valid_friction_still_solves() {
    let dir = tmpdir("degenerate-friction");
    let u_of = |name: &str, friction: &str| {
        let set = format!("contact.pair.0.friction={friction}");
        let s = common::solve(&root().join("run/seed.toml"), &["mesh.n=4", &set], &dir.join(format!("{name}.h5")));
        s.solution.displacement
    };
    let reference = u_of("unit", "{type=\"orthotropic\", g1=0.09, g2=0.03, direction=[1.0, 0.0, 1.0]}");
    let scale = common::max_abs(&reference);
    for (name, friction) in [
        ("direction-huge", "{type=\"orthotropic\", g1=0.09, g2=0.03, direction=[1e300, 0.0, 1e300]}"),
        ("direction-tiny", "{type=\"orthotropic\", g1=0.09, g2=0.03, direction=[1e-300, 0.0, 1e-300]}"),
    ] {
        let u = u_of(name, friction);
        let d = u.iter().flatten().zip(reference.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(d <= 1e-12 * scale, "{name}: u differs from the [1, 0, 1] direction's by {:.2e} relative", d / scale);
    }
    // a segment (no bound along x): the upper block slides further along x than on the ellipse
    let segment = u_of("g1-zero", "{type=\"orthotropic\", g1=0.0, g2=0.03, direction=[1.0, 0.0, 0.0]}");
    let ellipse = u_of("g1-009", "{type=\"orthotropic\", g1=0.09, g2=0.03, direction=[1.0, 0.0, 0.0]}");
    let ux = |u: &[[f64; 3]]| u.iter().fold(0.0f64, |a, v| a.max(v[0].abs()));
    assert!(
        segment.iter().flatten().all(|v| v.is_finite()) && ux(&segment) > ux(&ellipse),
        "g1 = 0: max |u_x| {:.4e} against {:.4e} with g1 = 0.09",
        ux(&segment),
        ux(&ellipse)
    );
}

/// The live monitor: each phase as it starts and one line per outer iteration on stdout, in
/// the order they happen, the summary after; `--quiet` leaves the summary only.
#[test]
fn solve_shows_phases_and_iterations_live_unless_quiet() {
    let dir = tmpdir("monitor");
    let out = dir.join("r.h5");
    let scene = root().join("run/seed.toml");
    let args = ["solve", scene.to_str().unwrap(), "--set", "mesh.n=5", "--out", out.to_str().unwrap()];
    let o = run(&args);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    let at = |needle: &str| text.find(needle).unwrap_or_else(|| panic!("no `{needle}` in {text}"));
    assert!(at("] iterate") < at("‖r̃‖/‖b‖") && at("‖r̃‖/‖b‖") < at("] recover") && at("] recover") < at("solver tssn:"), "{text}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    let outer = report["solver"]["outer_iterations"].as_u64().unwrap() as usize;
    let lines = text.lines().filter(|l| l.split_whitespace().count() == 8 && l.split_whitespace().all(|w| w.parse::<f64>().is_ok())).count();
    assert_eq!(lines, outer, "one line per outer iteration: {text}");
    let q = run(&[&args[..], &["--quiet"]].concat());
    let quiet = String::from_utf8_lossy(&q.stdout);
    assert!(!quiet.contains("] iterate") && !quiet.contains("‖r̃‖/‖b‖ ") && quiet.starts_with("tresca-feti "), "{quiet}");
}

/// The benchmark set's own scenes (`run/bench/*.toml`) stay valid: each checks, with the pairs
/// it is built for.
#[test]
fn the_benchmark_scenes_check() {
    for (scene, pairs) in [("plane_strain_rollers", 162), ("thin_clamped_plate", 121)] {
        let o = run(&["check", root().join(format!("run/bench/{scene}.toml")).to_str().unwrap()]);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{scene}: {}", String::from_utf8_lossy(&o.stderr));
        assert!(text.contains(&format!("contact: m = {pairs} pairs (node-to-node)")), "{scene}: {text}");
    }
}

#[test]
fn unwritable_output_is_one_line() {
    let o = run(&[
        "solve",
        root().join("run/seed.toml").to_str().unwrap(),
        "--set",
        "mesh.n=3",
        "--set",
        "contact.enabled=false",
        "--out",
        "/proc/no/such/dir/r.h5",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    assert!(e.starts_with("error: ") && e.contains("/proc/no/such/dir"), "{e}");
}

#[test]
fn missing_scene_file() {
    let o = run(&["solve", "/nonexistent/scene.toml"]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.trim().lines().count(), 1);
    assert!(e.contains("/nonexistent/scene.toml"), "{e}");
}

#[test]
fn check_prints_resolved_scene_and_sizes() {
    let o = run(&["check", root().join("run/seed.toml").to_str().unwrap(), "--set", "mesh.n=6"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains("nodes = [6, 6, 6]"), "{s}");
    assert!(s.contains("mesh: 2 bodies, 432 nodes, 250 hexahedra"), "{s}");
    assert!(s.contains("DOFs: n = 1296"), "{s}");
    assert!(s.contains("total applied load: (0.000000e0, 0.000000e0, -3.000000e0)"), "{s}");
    assert!(s.contains("contact pair 0: slave upper.zmin (36 nodes) against master lower.zmax (36 nodes)"), "{s}");
    assert!(s.contains("contact: m = 36 pairs (node-to-node), Σw = 2.000000e0"), "{s}");
    assert!(s.contains("multipliers: 36 normal + 72 tangential"), "{s}");
}

/// Runs `scene` (with `sets`) under mpirun with 1, 2 and 3 ranks; returns each run's stdout and
/// fields after checking the run.
fn on_1_2_3_ranks(name: &str, sets: &[&str]) -> Vec<(String, OutputData)> {
    on_1_2_3_ranks_of(&root().join("run/seed.toml"), name, sets, 0.0)
}

/// [`on_1_2_3_ranks`] of any scene, the fields equal to `tol` relative (0: bitwise).
fn on_1_2_3_ranks_of(scene: &Path, name: &str, sets: &[&str], tol: f64) -> Vec<(String, OutputData)> {
    let dir = tmpdir(name);
    let mut runs = Vec::new();
    for n in [1, 2, 3] {
        let out = dir.join(format!("r{n}.h5"));
        let mut args = vec!["solve", scene.to_str().unwrap(), "--out", out.to_str().unwrap()];
        for s in sets {
            args.extend(["--set", s]);
        }
        let o = mpirun(n, &args);
        let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(o.status.success(), "{n} ranks: {}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(stdout.matches("wrote ").count(), 1, "only rank 0 prints: {stdout}");
        assert!(stdout.contains(&format!("{n} rank(s)")), "{stdout}");
        let data = fields(&out);
        // the file records the rank count and each element's rank
        let ranks = data.attributes.iter().find(|a| a.0 == "ranks").map(|a| a.1.clone());
        assert_eq!(ranks, Some(n.to_string()));
        let rank = data.fields.iter().find(|f| f.name == "rank").expect("rank field");
        let Values::I32(r) = &rank.values else { panic!("rank field is not integer") };
        // two bodies at least (monolithic: one rank per body, the third idle)
        let busy = (0..n as i32).filter(|k| r.contains(k)).count();
        assert!(r.iter().all(|&x| (x as usize) < n) && busy >= n.min(2), "{n} ranks: {busy} hold elements");
        runs.push((stdout, data));
    }
    let counters = |s: &str| s.lines().find(|l| l.starts_with("solver ")).unwrap_or_else(|| panic!("{s}")).to_string();
    for (stdout, data) in &runs[1..] {
        // the same iteration counters, and the same results to the last bit (well within 1e-10)
        assert_eq!(counters(stdout), counters(&runs[0].0));
        // the mesh is written as each rank's rows: the same file whatever the rank count
        assert_eq!(data.coordinates, runs[0].1.coordinates);
        assert_eq!(data.cells, runs[0].1.cells);
        for (a, b) in data.fields.iter().zip(&runs[0].1.fields).filter(|(a, _)| a.name != "rank") {
            assert_eq!(a.name, b.name);
            if a.values != b.values {
                let d = match (&a.values, &b.values) {
                    (Values::F64(x), Values::F64(y)) => {
                        x.iter().zip(y).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max) / x.iter().fold(f64::MIN_POSITIVE, |m, v| m.max(v.abs()))
                    }
                    _ => f64::NAN,
                };
                assert!(d <= tol, "{name}: field {} differs between rank counts (max difference {d:.2e} relative)", a.name);
            }
        }
        assert_eq!(data.steps.len(), runs[0].1.steps.len());
        for (sa, sb) in data.steps.iter().zip(&runs[0].1.steps) {
            for (a, b) in sa.fields.iter().zip(&sb.fields) {
                assert!(tol > 0.0 || a.values == b.values, "step {}: field {} differs between rank counts", sa.time, a.name);
            }
        }
    }
    runs
}

#[test]
fn one_two_three_ranks_give_identical_fields() {
    // the monolithic dual (bodies on ranks, replicated dual vectors)
    on_1_2_3_ranks("ranks", &["mesh.n=6"]);
}

/// Bitwise rank-count independence beyond the Tresca seed: Coulomb (lagged bounds on TFETI,
/// the Newton method on the monolithic dual), orthotropic Tresca on TFETI, and a dual-mortar
/// model of 10-node tetrahedra from Gmsh. Orthotropic Tresca on the monolithic dual is not
/// bitwise: 1 rank against 2 and 3 (which agree bitwise) differs by 6.0e-15 relative in u with
/// the same counters (found 2026-12-05, not explained yet; not faer's threads): held to 1e-13.
#[test]
fn coulomb_orthotropic_and_tet10_mortar_are_bitwise_identical_on_1_2_3_ranks() {
    let coulomb = "contact.pair.0.friction={type=\"coulomb\", mu=0.3}";
    let ortho = "contact.pair.0.friction={type=\"orthotropic\", g1=0.09, g2=0.03, direction=[1.0, 1.0, 0.0]}";
    on_1_2_3_ranks("ranks-coulomb", &["mesh.n=6", coulomb]);
    on_1_2_3_ranks("ranks-coulomb-tfeti", &["mesh.n=8", coulomb, "decomposition.subdomains=4", "decomposition.tfeti=true"]);
    let dir = tmpdir("ranks-tet10");
    let scene = dir.join("tet10.toml");
    std::fs::write(&scene, gmsh_scene(&root().join("mesh/two_tet10_blocks.msh"))).unwrap();
    let runs = on_1_2_3_ranks_of(&scene, "ranks-tet10-mortar", &["decomposition.subdomains=2", "decomposition.tfeti=true"], 0.0);
    assert!(runs[0].0.contains("mesh: "), "{}", runs[0].0);
    on_1_2_3_ranks("ranks-orthotropic-tfeti", &["mesh.n=8", ortho, "decomposition.subdomains=4", "decomposition.tfeti=true"]);
    on_1_2_3_ranks_of(&root().join("run/seed.toml"), "ranks-orthotropic", &["mesh.n=6", ortho], 1e-13);
}

/// TFETI with distributed dual vectors: 4 subdomains per body over 1, 2, 3 ranks, with
/// friction, with the symmetrized solver and with TSSN's projected CG and the FETI Dirichlet
/// preconditioner (gathered (BBᵀ)⁻¹ groups, GΠGᵀ per Newton step), and the preconditioner in
/// SSN's BiCGSTAB, GIMSSN's CGMfeas and MPGP (whose face, and so GΠGᵀ, changes on one rank
/// only: the decision to restrict anew is collective), H-TFETI (clusters of 2, whole on a
/// rank), TSSN on the oblique operator with the explicit coarse inverse (each rank its
/// pieces' rows of C⁻¹), and a load path of three steps (each step's loads, held values and c
/// from the ranks' shares of the mesh); each rank reads the parallel HDF5 file back.
#[test]
fn tfeti_on_one_two_three_ranks_gives_identical_counters_and_fields() {
    for (name, method, pc, per_cluster) in [
        ("tfeti-ssn", "ssn-bicgstab", "none", 1),
        ("tfeti-gimssn", "gimssn", "none", 1),
        ("tfeti-tssn-dirichlet", "tssn", "dirichlet", 1),
        ("tfeti-ssn-lumped", "ssn-bicgstab", "lumped", 1),
        ("tfeti-gimssn-dirichlet", "gimssn", "dirichlet", 1),
        ("tfeti-mpgp-lumped", "mpgp", "lumped", 1),
        ("htfeti-tssn-lumped", "tssn", "lumped", 2),
        ("tfeti-tssn-explicit", "tssn", "none", 1),
        ("tfeti-tssn-path", "tssn", "none", 1),
    ] {
        let m = format!("solver.method=\"{method}\"");
        let p = format!("solver.preconditioner=\"{pc}\"");
        let c = format!("decomposition.subdomains_per_cluster={per_cluster}");
        let mut sets = vec!["mesh.n=8", "solver.eps=1e-6", "decomposition.subdomains=4", "decomposition.tfeti=true", &m, &p, &c, "output.verify=true"];
        if name.ends_with("explicit") {
            sets.extend(["decomposition.projected_cg=false", "decomposition.coarse_solve=\"explicit\""]);
        }
        if name.ends_with("path") {
            sets.extend(["load.steps=3", "decomposition.dirichlet=\"eliminated\""]);
        }
        // ε = 1e-6: GIMSSN stalls near 5e-8 on this TFETI dual (README)
        let runs = on_1_2_3_ranks(name, &sets);
        for (n, (stdout, _)) in runs.iter().enumerate() {
            assert!(stdout.contains(&format!("values on {} ranks match the fields in memory", n + 1)), "{stdout}");
        }
    }
}

#[test]
fn bad_scene_under_mpirun_fails_once_on_all_ranks() {
    let dir = tmpdir("mpi-bad");
    let out = dir.join("r.h5");
    let o = mpirun(2, &["solve", root().join("run/seed.toml").to_str().unwrap(), "--set", "mesh.n=1", "--out", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.matches("error: mesh.n").count(), 1, "{e}");
    assert!(!out.exists());
}

/// An error on one rank only (a factorization failing on rank 1, injected) and no convergence
/// under TFETI: one message, a non-zero exit, no result files, no hang.
#[test]
fn failure_on_one_rank_or_no_convergence_stops_all_ranks() {
    let dir = tmpdir("mpi-fail");
    let scene = root().join("run/seed.toml");
    let tfeti = ["--set", "mesh.n=6", "--set", "decomposition.subdomains=2", "--set", "decomposition.tfeti=true"];
    for (case, extra, env, expect) in [
        ("fault", vec![], Some("factorize@1"), "injected fault: phase factorize on rank 1"),
        ("noconv", vec!["--set", "solver.max_outer=2"], None, "no convergence in 2 outer iterations"),
    ] {
        let out = dir.join(format!("{case}.h5"));
        let mut args = vec!["solve", scene.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend(tfeti);
        args.extend(extra);
        let mut cmd = mpirun_cmd(2, &args);
        if let Some(f) = env {
            cmd.env("TRESCA_FETI_FAULT", f);
        }
        let o = cmd.output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{case}");
        assert_eq!(e.matches("error: ").count(), 1, "{case}: {e}");
        assert!(e.contains(expect), "{case}: {e}");
        for ext in ["h5", "xdmf", "json"] {
            assert!(!out.with_extension(ext).exists(), "{case}: {ext} left behind");
        }
        let temps: Vec<_> =
            std::fs::read_dir(out.parent().unwrap()).into_iter().flatten().flatten().filter(|e| e.file_name().to_string_lossy().ends_with(".tmp")).collect();
        assert!(temps.is_empty(), "{case}: temporary files left behind");
    }
}

/// `bench-coarse`: one row per subdomain count, the coarse dimension growing with it, the
/// explicit rows of more pieces per rank taking more bytes; a bad count is one line.
#[test]
fn bench_coarse_prints_one_row_per_subdomain_count() {
    let scene = root().join("run/seed.toml");
    let o = run(&["bench-coarse", "--scene", scene.to_str().unwrap(), "--set", "mesh.n=8", "--subdomains", "4,16", "--pieces", "1,4", "--repeat", "2"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: Vec<Vec<f64>> =
        stdout.lines().skip(1).map(|l| l.split(|c: char| c.is_whitespace() || c == '|').filter_map(|x| x.parse().ok()).collect()).collect();
    assert_eq!(rows.len(), 2, "{stdout}");
    // S, pieces, dim, nnz(C), nnz(L), build, factor solve, then (MB, setup, product) per pieces
    assert!(rows.iter().all(|r| r.len() == 13), "{stdout}");
    assert_eq!((rows[0][0], rows[1][0]), (8.0, 32.0));
    assert!(rows[1][2] > rows[0][2] && rows[1][10] > rows[1][7], "{stdout}");
    let o = run(&["bench-coarse", "--scene", scene.to_str().unwrap(), "--subdomains", "0"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.trim().lines().count() == 1 && e.contains("decomposition.subdomains"), "{e}");
}

#[test]
fn table1_prints_the_table_and_writes_the_csv() {
    let dir = tmpdir("table1");
    let csv = dir.join("t.csv");
    let scene = root().join("run/seed.toml");
    let o = run(&[
        "table1",
        "--scene",
        scene.to_str().unwrap(),
        "--sizes",
        "4,5",
        "--eps",
        "1e-6",
        "--solvers",
        "gimssn,imssn:paper,ssn-bicgstab",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("imssn:paper") && stdout.contains("paper IMSSN"), "{stdout}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + 2 * 3, "{text}");
    assert!(lines[0].starts_with("N,n,m,solver,preset,eps,iter,nA"));
    for l in &lines[1..] {
        let f: Vec<&str> = l.split(',').collect();
        assert_eq!(f.last(), Some(&"ok"), "{l}");
        // converged: final ‖r̃‖/‖b‖ ≤ ε, KKT small, u close to the reference
        assert!(f[11].parse::<f64>().unwrap() <= 1e-6, "{l}");
        assert!(f[12].parse::<f64>().unwrap() <= 1e-5, "{l}");
        assert!(f[13].parse::<f64>().unwrap() <= 1e-3, "{l}");
    }
    assert_eq!(lines[1].split(',').nth(4), Some("default"));
    assert_eq!(lines[2].split(',').nth(4), Some("paper"));
    let o = run(&["table1", "--sizes", "4", "--solvers", "newton"]);
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.starts_with("error: ") && stderr.contains("unknown solver \"newton\""), "{stderr}");
    // the preconditioned TSSN needs TFETI: table1 (monolithic) refuses it before any solve
    let o = run(&["table1", "--sizes", "4", "--solvers", "tssn:dirichlet"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.lines().count() == 1 && stderr.contains("tssn:dirichlet needs TFETI"), "{stderr}");
    assert!(o.stdout.is_empty(), "nothing printed before the refusal");
    // a CSV that cannot be written fails before the run, with nothing left behind
    let o = run(&["table1", "--sizes", "4", "--csv", "/proc/no-such-dir/t.csv"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stdout).is_empty());
    assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: /proc/no-such-dir"));
}

/// Usage errors as clap formats them, exit code 2: the help with its first-run lines for a
/// missing command, the error and the usage line otherwise; under mpirun from one rank only.
#[test]
fn usage_errors_as_clap_prints_them_once() {
    let o = run(&[]);
    let help = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{help}");
    assert!(help.lines().count() > 10 && help.contains("A first run:") && help.contains("Commands:"), "{help}");
    assert!(help.lines().all(|l| l.chars().count() <= 200), "readable lines: {help}");
    for args in [&["solve"][..], &["solve", "x.toml", "--bogus"], &["table1", "--sizes", "a"], &["sovle", "x.toml"]] {
        let o = run(args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.starts_with("error: ") && stderr.contains("try '--help'"), "{args:?}: {stderr}");
        assert!((2..=8).contains(&stderr.trim().lines().count()), "{args:?}: {stderr}");
    }
    // under a launcher: printed by the first rank only
    for args in [&[][..], &["solve"]] {
        let o = mpirun(2, args);
        let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        assert!(!o.status.success(), "{all}");
        assert_eq!(all.matches("\nUsage: tresca-feti").count(), 1, "{args:?}: {all}");
    }
}

/// Every printed length, area, force and stress carries the scene's unit names: the step lines
/// of a load path, the summary, and `check`'s faces, tractions, load and gaps.
#[test]
fn units_where_they_are_printed() {
    let seed = root().join("run/seed.toml");
    let units = ["--set", "units.length=\"mm\"", "--set", "units.force=\"N\"", "--set", "mesh.n=4", "--set", "load.steps=2"];
    let dir = tmpdir("units");
    let out = dir.join("u.h5");
    let mut args = vec!["solve", seed.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(&units);
    let o = run(&args);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let steps: Vec<&str> = text.lines().filter(|l| l.contains("] load step ")).collect();
    assert_eq!(steps.len(), 2, "{text}");
    for l in steps {
        assert!(l.contains(") N, max |u| ") && l.contains(" mm, "), "{l}");
    }
    assert!(text.lines().any(|l| l.starts_with("contact:") && l.ends_with(" N")), "{text}");
    assert!(text.lines().any(|l| l.starts_with("max |u| = ") && l.contains(" mm (body") && l.ends_with(" MPa")), "{text}");
    let mut args = vec!["check", seed.to_str().unwrap()];
    args.extend_from_slice(&units);
    let o = run(&args);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let faces: Vec<&str> = text.lines().filter(|l| l.contains(" nodes, area ")).collect();
    assert!(!faces.is_empty() && faces.iter().all(|l| l.ends_with(" mm²")), "{text}");
    let tractions: Vec<&str> = text.lines().filter(|l| l.starts_with("traction[")).collect();
    assert!(!tractions.is_empty(), "{text}");
    for l in tractions {
        assert!(l.contains(") MPa over area ") && l.contains(" mm², resultant (") && l.contains(") N at factor 1"), "{l}");
    }
    assert!(text.lines().any(|l| l.starts_with("total applied load: (") && l.ends_with(") N")), "{text}");
    assert!(text.lines().any(|l| l.starts_with("contact: m = ") && l.contains(" mm², gaps in [") && l.contains("] mm, ")), "{text}");
}

/// Counters that mean what they say: "on the slip bound" counts slipping (closed) pairs only,
/// never more than slip, and the summary says what the rest of the slipping pairs do; a run
/// that took no product in single precision does not announce mixed precision.
#[test]
fn counters_mean_what_they_say() {
    let dir = tmpdir("counters");
    // the seed at N = 4: half its pairs open, their tangential multipliers on the Tresca bound
    let out = dir.join("seed.h5");
    let o = run(&["solve", root().join("run/seed.toml").to_str().unwrap(), "--set", "mesh.n=4", "-q", "--out", out.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("seed.json")).unwrap()).unwrap();
    let c = &report["contact"];
    let (open, slip, bound) = (c["open"].as_u64().unwrap(), c["slip"].as_u64().unwrap(), c["on_slip_bound"].as_u64().unwrap());
    assert!(open > 0 && slip > 0 && bound <= slip, "{c}");
    let line = text.lines().find(|l| l.starts_with("contact: ")).unwrap();
    assert!(line.contains(&format!("{slip} slip; ")), "{line}");
    assert!(
        line.contains("every slipping pair on the slip bound")
            || line.contains(&format!("of the slipping pairs {bound} on the slip bound, {} sliding within ε inside it", slip - bound)),
        "{line}"
    );
    // a body held by contact alone, solved by SSN-BiCGSTAB on exact products only
    let out = dir.join("floating.h5");
    let o = run(&["solve", root().join("run/validation/floating_block.toml").to_str().unwrap(), "-q", "--out", out.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("floating.json")).unwrap()).unwrap();
    assert_eq!(report["solver"]["inexact_products"].as_u64(), Some(0), "{text}");
    let solver = text.lines().find(|l| l.starts_with("solver ")).unwrap();
    assert!(!solver.contains("mixed precision"), "{solver}");
    // and where products were single precision, it is said with their count
    let out = dir.join("tfeti.h5");
    let o = run(&[
        "solve",
        root().join("run/seed.toml").to_str().unwrap(),
        "--set",
        "mesh.n=8",
        "--set",
        "decomposition.subdomains=2",
        "-q",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("tfeti.json")).unwrap()).unwrap();
    let n = report["solver"]["inexact_products"].as_u64().unwrap();
    let solver = text.lines().find(|l| l.starts_with("solver ")).unwrap();
    assert_eq!(n > 0, solver.contains(&format!("mixed precision ({n} products in single precision")), "{solver}");
}

/// `check --ranks P` predicts what `solve` picks under `mpirun -n P`: the same chosen
/// candidate of the decomposition plan and the same dual (the seed at N = 16 and 24, the
/// tutorial, the roller slabs; 2 ranks).
#[test]
fn check_with_ranks_predicts_the_decomposition_solve_picks() {
    let dir = tmpdir("check-ranks");
    for (name, scene, sets) in [
        ("seed16", "run/seed.toml", vec!["mesh.n=16"]),
        ("seed24", "run/seed.toml", vec!["mesh.n=24"]),
        ("tutorial", "run/tutorial.toml", vec![]),
        ("slabs", "run/bench/plane_strain_rollers.toml", vec![]),
    ] {
        let scene = root().join(scene);
        let mut args = vec!["check", scene.to_str().unwrap(), "--ranks", "2"];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let o = run(&args);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        let chosen = text.lines().find(|l| l.ends_with("← chosen")).unwrap_or_else(|| panic!("{name}: {text}"));
        // the label, up to the figures' basis column (counted, model, bound) or the first number
        let basis = ["counted", "model", "bound"];
        let predicted = chosen.split_whitespace().take_while(|w| *w != "-" && !basis.contains(w) && w.parse::<f64>().is_err()).collect::<Vec<_>>().join(" ");
        let dual = text.lines().find_map(|l| l.strip_prefix("dual: ")).unwrap().to_string();
        let out = dir.join(format!("{name}.h5"));
        let mut args = vec!["solve", scene.to_str().unwrap(), "-q", "--out", out.to_str().unwrap()];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let o = mpirun(2, &args);
        assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap()).unwrap();
        let plan = report["decomposition_plan"].as_array().unwrap_or_else(|| panic!("{name}: no plan in the report"));
        let best = plan.iter().min_by(|a, b| a["time"].as_f64().unwrap().total_cmp(&b["time"].as_f64().unwrap())).unwrap();
        let picked = if best["tfeti"].as_bool().unwrap() {
            let p: Vec<String> = best["parts"].as_array().unwrap().iter().map(|v| v.to_string()).collect();
            format!("TFETI {}", p.join("/"))
        } else {
            "monolithic".to_string()
        };
        assert_eq!(predicted, picked, "{name}: check predicted `{chosen}`");
        let problem = report["problem"].as_str().unwrap();
        assert!(
            problem.contains(&format!("({} dual)", if dual == "TFETI" { "TFETI" } else { "monolithic" })),
            "{name}: check said dual {dual}, solve: {problem}"
        );
    }
}

/// `check` refuses what `solve` refuses after the plan, with the same line: a load path
/// without contact, an FCLIB export without a Coulomb pair, the monolithic dual's export on a
/// TFETI scene (before, `check` passed them).
#[test]
fn check_refuses_what_solve_refuses() {
    let dir = tmpdir("check-like-solve");
    let seed = root().join("run/seed.toml");
    let fclib = format!("output.export_fclib=\"{}\"", dir.join("f.h5").display());
    let dual = format!("output.export_dual=\"{}\"", dir.join("d.h5").display());
    for (sets, key) in [
        (vec!["mesh.n=4", "contact.enabled=false", "load.steps=2"], "load.steps"),
        (vec!["mesh.n=4", fclib.as_str()], "output.export_fclib"),
        (vec!["mesh.n=4", dual.as_str(), "decomposition.subdomains=2", "decomposition.tfeti=true"], "output.export_dual"),
    ] {
        let mut lines = Vec::new();
        for cmd in ["check", "solve"] {
            let out = dir.join("r.h5");
            let mut args = vec![cmd, seed.to_str().unwrap()];
            if cmd == "solve" {
                args.extend(["-q", "--out", out.to_str().unwrap()]);
            }
            for s in &sets {
                args.extend(["--set", s]);
            }
            let o = run(&args);
            let err = String::from_utf8_lossy(&o.stderr).trim().to_string();
            assert_eq!(o.status.code(), Some(1), "{cmd} {sets:?}: {err}");
            assert!(err.lines().count() == 1 && err.starts_with(&format!("error: {key}:")), "{cmd} {sets:?}: {err}");
            lines.push(err);
        }
        assert_eq!(lines[0], lines[1], "check and solve say the same");
    }
}
