//! Tests of the scene parser: curved box sides (geometry of the built mesh, validation).

use super::*;

const SPHERE_SCENE: &str = r#"
[mesh]
n = 5
[[material]]
name = "m"
E = 1.0
nu = 0.3
[[body]]
name = "cap"
material = "m"
box = { min = [0.0, 0.0, 1.0], max = [1.0, 2.0, 2.0], nodes = [5, 9, 3], sphere = { side = "zmin", radius = 4.0, centre = [0.0, 0.0] } }
[[dirichlet]]
face = "cap.zmax"
[contact]
enabled = false
"#;

#[test]
fn sphere_bulge_geometry() {
    let scene = parse(SPHERE_SCENE, "t", &[]).expect("valid");
    let bx = scene.bodies[0].boxed.as_ref().unwrap();
    let (r, h2) = (4.0f64, 1.0f64 + 4.0);
    // pole at the corner (0, 0): full sagitta there, 0 at the farthest corner (1, 2)
    assert!((bx.bulge(0.0, 0.0) - (r - (r * r - h2).sqrt())).abs() < 1e-14);
    assert!(bx.bulge(1.0, 2.0).abs() < 1e-14);
    assert!((bx.bulge(0.6, 0.8) - ((r * r - 1.0).sqrt() - (r * r - h2).sqrt())).abs() < 1e-14);
    // rotationally symmetric about the pole's line, ≥ 0 over the side
    assert_eq!(bx.bulge(0.0, 1.0), bx.bulge(1.0, 0.0));
    for i in 0..=10 {
        for j in 0..=20 {
            assert!(bx.bulge(0.1 * i as f64, 0.1 * j as f64) >= -1e-15);
        }
    }
    // the default centre is the side's centre: the half-diagonal is the reach
    let mut centred = bx.clone();
    centred.sphere.as_mut().unwrap().centre = None;
    assert_eq!(centred.sphere.as_ref().unwrap().pole(&centred), [0.5, 1.0]);
    assert!((centred.sphere.as_ref().unwrap().reach(&centred) - 1.25f64.sqrt()).abs() < 1e-15);
    assert!(centred.bulge(0.0, 0.0).abs() < 1e-14 && centred.bulge(1.0, 2.0).abs() < 1e-14);
    // the built mesh: the zmin nodes lie on the sphere of radius R centred above the pole,
    // the zmax nodes stay flat, the ones between in proportion
    let model = crate::model::build(&LoadedScene { scene, path: "t.toml".into() }).expect("builds");
    let zc = 1.0 + (r * r - h2).sqrt(); // the sphere's centre: the far corner at z = 1
    let (mut low, mut top) = (0, 0);
    for p in &model.mesh.nodes {
        let b = (r * r - p[0] * p[0] - p[1] * p[1]).sqrt() - (r * r - h2).sqrt();
        if p[2] < 1.0 + 1e-12 {
            low += 1;
            assert!(((p[0] * p[0] + p[1] * p[1] + (p[2] - zc) * (p[2] - zc)).sqrt() - r).abs() < 1e-12, "{p:?} off the sphere");
        } else if (p[2] - 2.0).abs() < 1e-12 {
            top += 1;
        } else {
            assert!((p[2] - (1.5 - b * 0.5)).abs() < 1e-12, "{p:?} not in proportion");
        }
    }
    assert_eq!((low, top), (45, 45));
}

#[test]
fn sphere_is_validated() {
    let bad = |from: &str, to: &str, key: &str| {
        let text = SPHERE_SCENE.replace(from, to);
        let e = parse(&text, "t", &[]).expect_err(to).to_string();
        assert!(e.contains(key), "{to}: {e}");
    };
    // the radius must exceed the reach √5 of the corner pole (and the half-diagonal by default)
    bad("radius = 4.0", "radius = 2.2", "box.sphere.radius");
    bad("radius = 4.0, centre = [0.0, 0.0]", "radius = 1.1", "box.sphere.radius");
    bad("side = \"zmin\"", "side = \"xmin\"", "box.sphere.side");
    bad("nodes = [5, 9, 3],", "nodes = [5, 9, 3], cylinder = { side = \"zmin\", radius = 4.0 },", "box.sphere");
    // a cap higher than the box
    bad("max = [1.0, 2.0, 2.0]", "max = [1.0, 2.0, 1.2]", "bulge more than");
    assert!(parse(&SPHERE_SCENE.replace(", centre = [0.0, 0.0]", ""), "t", &[]).is_ok());
}
