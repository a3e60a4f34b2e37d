//! The maintainer's map against the tree: docs/ARCHITECTURE.md names every source file, in the
//! row of its top folder under `src/` (a file at the top of `src/`, anywhere in the map).

use crate::common::source_files;
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
