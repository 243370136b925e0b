//! Times the model build of a scene on one process: the Gmsh parse alone (`read_many` of every
//! body of the file given as the second argument, if any), then `mesh read`, `pairing`, `hold
//! buckets` and `hold check` as the time table splits them.
//!
//!     cargo run --release --example mesh_read_bench -- SCENE.toml [MESH.msh VOLUME...]

use std::path::Path;
use std::time::Instant;

fn main() -> tresca_feti::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(scene) = args.first() else {
        eprintln!("usage: mesh_read_bench SCENE.toml [MESH.msh VOLUME...]");
        std::process::exit(2);
    };
    if let Some(msh) = args.get(1) {
        let volumes: Vec<Option<&str>> = args[2..].iter().map(|v| Some(v.as_str())).collect();
        let clock = Instant::now();
        let bodies = tresca_feti::mesh::gmsh::read_many(Path::new(msh), &volumes)?;
        let secs = clock.elapsed().as_secs_f64();
        let cells: usize = bodies.iter().filter_map(|b| b.as_ref().ok()).map(|b| b.cells.len()).sum();
        println!("gmsh parse       {secs:8.3} s  ({} bodies, {cells} cells)", bodies.len());
    }
    let ls = tresca_feti::scene::load(Path::new(scene), &[])?;
    let mut times = Vec::new();
    let clock = Instant::now();
    let mut model = tresca_feti::model::build_timed(&ls, &mut times, &|_, _| ())?;
    let build = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    model.check_held()?;
    times.push(("hold check", clock.elapsed().as_secs_f64()));
    for (name, secs) in &times {
        println!("{name:<16} {secs:8.3} s");
    }
    println!("model build      {build:8.3} s  ({} nodes)", model.mesh.nodes.len());
    Ok(())
}
