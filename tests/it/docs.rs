//! The maintainer's map against the tree: docs/ARCHITECTURE.md names every source file, in the
//! row of its top folder under `src/` (a file at the top of `src/`, anywhere in the map).

use crate::common::{root, scratch, source_files, stderr, tmc};
use std::path::Path;

#[test]
fn the_architecture_names_every_source_file_in_its_folders_row() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let map = std::fs::read_to_string(root.join("docs/ARCHITECTURE.md")).unwrap();
    let files = source_files();
    assert!(files.len() > 50, "{} source files", files.len());
    let row = |folder: &str| {
        let head = format!("| `{folder}/` |");
        map.lines().find(|l| l.starts_with(&head)).unwrap_or("")
    };
    let missing: Vec<String> = (files.iter())
        .filter(|f| {
            let name = format!("`{}`", f.file_name().unwrap().to_string_lossy());
            // a file in a folder of a folder is named in its top folder's row
            let top = f.components().next().and_then(|c| c.as_os_str().to_str());
            match top.filter(|_| f.components().count() > 1) {
                Some(folder) => !row(folder).contains(&name),
                None => !map.contains(&name) && !map.contains(&format!("`src/{}", &name[1..])),
            }
        })
        .map(|f| f.display().to_string())
        .collect();
    assert!(
        missing.is_empty(),
        "docs/ARCHITECTURE.md does not name these source files in their folder's row: {missing:?}"
    );
}

/// The keys a case file may hold: each field of a `deny_unknown_fields` struct of `src/case/`
/// (the tables serde reads a case into). A field added there is a key users can write.
fn case_keys() -> Vec<(String, String)> {
    let dir = root().join("src/case");
    let mut keys = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let file = path.file_name().unwrap().to_string_lossy().into_owned();
        let mut i = 0;
        while i < lines.len() {
            if !lines[i].contains("deny_unknown_fields") {
                i += 1;
                continue;
            }
            while !lines[i].contains("struct ") {
                i += 1;
            }
            i += 1;
            while !lines[i].starts_with('}') {
                let field = lines[i].trim_start().trim_start_matches("pub ");
                if let Some((name, _)) = field.split_once(": ") {
                    let name = name.trim();
                    if !name.is_empty() && name.chars().all(|c| c.is_alphanumeric() || c == '_') {
                        keys.push((file.clone(), name.to_string()));
                    }
                }
                i += 1;
            }
        }
    }
    keys
}

#[test]
fn the_case_reference_names_every_key_the_parser_takes() {
    let doc = std::fs::read_to_string(root().join("docs/CASE.md")).unwrap();
    let keys = case_keys();
    // the tables of the top level, a region, friction, a bc, radiation, steps, time, solver,
    // petsc, output, units, probe, mesh_options: some 90 keys
    assert!(
        keys.len() > 80,
        "{} keys found in src/case/: {keys:?}",
        keys.len()
    );
    let missing: Vec<_> = (keys.iter())
        .filter(|(_, k)| {
            let named = [
                format!("`{k}`"),
                format!("[{k}]"),
                format!("[[{k}]]"),
                format!(".{k}]"),
            ];
            !named.iter().any(|n| doc.contains(n))
        })
        .collect();
    assert!(
        missing.is_empty(),
        "docs/CASE.md does not name these keys: {missing:?}"
    );
}

#[test]
fn the_case_references_whole_example_is_a_case_tmc_accepts() {
    let doc = std::fs::read_to_string(root().join("docs/CASE.md")).unwrap();
    let example = (doc.split("```toml\n").skip(1))
        .map(|b| b.split("```").next().unwrap())
        .find(|b| b.starts_with("mesh = "))
        .expect("docs/CASE.md has a whole case, a toml block that starts with `mesh = `");
    // its mesh path is relative to cases/, where a user's case would sit
    let dir = scratch("whole-case");
    let text = example.replace("\"../geo/", &format!("\"{}/geo/", root().display()));
    let case = dir.join("case.toml");
    std::fs::write(&case, text).unwrap();
    let o = tmc(&["check", case.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("ready to solve"), "{out}");
}
