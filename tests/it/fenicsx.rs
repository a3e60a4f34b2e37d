//! tmc against FEniCSx (Debian's python3-dolfinx 0.5.2) on the same meshes: a 2D and a 3D
//! scene of `validation/fenicsx/` (and the quadratic tri6 one, the 3D one in Mooney-Rivlin and
//! the 2D one radiating from its hole) must agree node by node to 1e-8 of the solution's
//! max-norm (`make validate` runs all eight scenes and writes RESULTS.md).

use crate::common;
use common::*;
use std::process::Command;

fn compare(cases: &[&str]) {
    let work = scratch(&format!("fenicsx-{}", cases.join("-")));
    let out = Command::new("/usr/bin/python3")
        .arg(root().join("validation/fenicsx/run.py"))
        .arg(env!("CARGO_BIN_EXE_tmc"))
        .arg(&work)
        .args(cases)
        .output()
        .expect("/usr/bin/python3 runs (make deps installs python3-dolfinx, python3-gmsh)");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "FEniCSx comparison failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for c in cases {
        assert!(
            stdout.contains(&format!("| {c} |")),
            "{c} missing:\n{stdout}"
        );
    }
}

#[test]
fn t1_plate_with_hole_matches_fenicsx() {
    compare(&["plate-hole-t1"]);
}

#[test]
fn h1_block_with_hole_matches_fenicsx() {
    compare(&["block-hole-h1"]);
}

#[test]
fn a_mooney_rivlin_block_with_hole_matches_fenicsx() {
    compare(&["block-hole-h1-mr"]);
}

#[test]
fn a_plate_radiating_from_its_hole_matches_fenicsx() {
    compare(&["plate-hole-t1-rad"]);
}

#[test]
fn t2_plate_with_curved_hole_matches_fenicsx() {
    compare(&["plate-hole-t2"]);
}
