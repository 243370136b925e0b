//! Records the versions of the main dependencies (from Cargo.lock) for the result files.
fn main() {
    println!("cargo:rerun-if-changed=Cargo.lock");
    let lock = std::fs::read_to_string("Cargo.lock").unwrap_or_default();
    let wanted = ["faer", "mpi", "hdf5-metno", "metis", "mshio", "toml"];
    let mut found = Vec::new();
    let mut name = String::new();
    for line in lock.lines() {
        if let Some(v) = line.strip_prefix("name = ") {
            name = v.trim_matches('"').to_string();
        } else if let Some(v) = line.strip_prefix("version = ") {
            if wanted.contains(&name.as_str()) {
                found.push(format!("{name} {}", v.trim_matches('"')));
            }
        }
    }
    println!("cargo:rustc-env=TRESCA_DEP_VERSIONS={}", found.join(", "));
}
