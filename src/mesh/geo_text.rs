//! What tmc reads from a `.geo` file's text itself: the names its `DefineConstant[...]`
//! declares (the parameters `--set` and `[mesh_options] params` may set).

use std::path::Path;

/// Append the names declared by `DefineConstant[...]` in `geo` and in the files it
/// `Include`s (relative to its folder), in order of appearance.
pub fn define_constants(geo: &Path, names: &mut Vec<String>, depth: usize) -> std::io::Result<()> {
    let text = String::from_utf8_lossy(&std::fs::read(geo)?).into_owned();
    let code = strip_comments(&text);
    let mut rest = code.as_str();
    while let Some(k) = rest.find("DefineConstant") {
        rest = &rest[k + "DefineConstant".len()..];
        let body = rest.trim_start();
        let Some(body) = body.strip_prefix('[') else {
            continue;
        };
        for entry in top_level(body, ']') {
            let name = entry.split('=').next().unwrap_or("").trim();
            if !name.is_empty()
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                && !names.iter().any(|n| n == name)
            {
                names.push(name.to_string());
            }
        }
    }
    if depth < 8 {
        let dir = geo.parent().unwrap_or(Path::new("."));
        let mut rest = code.as_str();
        while let Some(k) = rest.find("Include") {
            rest = &rest[k + "Include".len()..];
            let quoted = rest
                .trim_start()
                .strip_prefix('"')
                .and_then(|r| r.split_once('"'));
            if let Some((file, _)) = quoted {
                let path = dir.join(file);
                if path.is_file() {
                    define_constants(&path, names, depth + 1)?;
                }
            }
        }
    }
    Ok(())
}

/// The text without `//` and `/* */` comments (strings kept).
fn strip_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    let mut in_string = false;
    while let Some(c) = chars.next() {
        if in_string {
            out.push(c);
            if c == '"' {
                in_string = false;
            }
            continue;
        }
        match (c, chars.peek()) {
            ('"', _) => {
                in_string = true;
                out.push(c);
            }
            ('/', Some('/')) => {
                for d in chars.by_ref() {
                    if d == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            ('/', Some('*')) => {
                chars.next();
                let mut prev = ' ';
                for d in chars.by_ref() {
                    if prev == '*' && d == '/' {
                        break;
                    }
                    prev = d;
                }
                out.push(' ');
            }
            _ => out.push(c),
        }
    }
    out
}

/// The comma-separated entries of `body` up to its closing `close` (brackets, braces and
/// strings nested inside entries are skipped over).
fn top_level(body: &str, close: char) -> Vec<&str> {
    let mut entries = Vec::new();
    let (mut depth, mut start, mut in_string) = (0usize, 0usize, false);
    for (i, c) in body.char_indices() {
        match c {
            '"' => in_string = !in_string,
            _ if in_string => {}
            '[' | '{' | '(' => depth += 1,
            c2 if c2 == close && depth == 0 => {
                entries.push(&body[start..i]);
                return entries;
            }
            ']' | '}' | ')' => depth = depth.saturating_sub(1),
            ',' if depth == 0 => {
                entries.push(&body[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    entries
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_of_define_constant() {
        let dir = std::env::temp_dir().join(format!("tmc-geo-text-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("inc.geo"),
            "DefineConstant[ r = {0.5, Min 0, Max 1, Name \"Parameters/r, radius\"} ];\n",
        )
        .unwrap();
        let geo = dir.join("main.geo");
        std::fs::write(
            &geo,
            "// DefineConstant[ commented = 1 ];\n/* DefineConstant[ c2 = 2 ]; */\n\
             DefineConstant[ W = 2.0, H = {1, Name \"a,b\"}, n = 32 ];\nh = 0.1;\nInclude \"inc.geo\";\n",
        )
        .unwrap();
        let mut names = Vec::new();
        define_constants(&geo, &mut names, 0).unwrap();
        assert_eq!(names, ["W", "H", "n", "r"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
