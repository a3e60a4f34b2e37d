//! `--set` and a study's `set`: a dotted path into the case's TOML, entries of an array of
//! tables picked by group or name.

/// Set `path` (dotted) in the case `doc` to `value`. In an array of tables (`[[bc]]`,
/// `[[region]]`, `[[probe]]`) the segment after its name picks an entry by its `group` or
/// `name`: `bc.top.uy`; where several match, `bc.bottom#2.theta` picks the second of them in
/// file order, and without `#N` the error lists them, with their lines when `text` (the case
/// file's source) is given.
pub fn set_path(
    doc: &mut toml::Table,
    path: &str,
    value: toml::Value,
    text: Option<&str>,
) -> Result<(), String> {
    set_path_making(doc, path, value, text).map(|_| ())
}

/// [`set_path`], and the dotted path of the first table it had to make (one the case does
/// not have), if any: a table made with one key alone may lack what it needs.
pub fn set_path_making(
    doc: &mut toml::Table,
    path: &str,
    value: toml::Value,
    text: Option<&str>,
) -> Result<Option<String>, String> {
    let mut made = None;
    set_in(doc, "", path, value, text, &mut made)?;
    Ok(made)
}

/// [`set_path`] below the dotted path `above` (where `doc` stands), the first table made
/// into `made`.
fn set_in(
    doc: &mut toml::Table,
    above: &str,
    path: &str,
    value: toml::Value,
    text: Option<&str>,
    made: &mut Option<String>,
) -> Result<(), String> {
    let segs: Vec<&str> = path.split('.').collect();
    let under = |n: usize| match above {
        "" => segs[..n].join("."),
        _ => format!("{above}.{}", segs[..n].join(".")),
    };
    let mut cur: &mut toml::Table = doc;
    for (i, seg) in segs.iter().enumerate() {
        if i + 1 == segs.len() {
            cur.insert(seg.to_string(), value);
            return Ok(());
        }
        if made.is_none() && !cur.contains_key(*seg) {
            *made = Some(under(i + 1));
        }
        let entry = cur
            .entry(seg.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            toml::Value::Array(items) => {
                // the entry segment: GROUP or NAME, then #N (from 1) among those that match
                let next = segs[i + 1];
                let (key, nth) = match next.split_once('#') {
                    Some((k, n)) => match n.parse::<usize>() {
                        Ok(n) if n >= 1 => (k, Some(n)),
                        _ => {
                            return Err(format!(
                                "\"{path}\": \"#{n}\" is no entry number (they count from 1 in \
                                 file order)"
                            ));
                        }
                    },
                    None => (next, None),
                };
                let matches = |t: &toml::Table| {
                    ["group", "name"]
                        .iter()
                        .any(|k| t.get(*k).and_then(|g| g.as_str()) == Some(key))
                };
                let found: Vec<usize> = (0..items.len())
                    .filter(|&k| items[k].as_table().is_some_and(matches))
                    .collect();
                let pick = match (nth, found.len()) {
                    (_, 0) => {
                        return Err(format!(
                            "\"{path}\": no [[{seg}]] with group or name \"{key}\""
                        ));
                    }
                    (None, 1) => found[0],
                    (Some(n), m) if n <= m => found[n - 1],
                    (nth, m) => {
                        let lines = entry_lines(text, seg);
                        let list: Vec<String> = found
                            .iter()
                            .enumerate()
                            .map(|(r, &k)| match lines.get(k) {
                                Some(l) => format!("{seg}.{key}#{} (line {l})", r + 1),
                                None => format!("{seg}.{key}#{}", r + 1),
                            })
                            .collect();
                        let why = match nth {
                            Some(n) => format!("there is no #{n}"),
                            None => "say which".to_string(),
                        };
                        return Err(format!(
                            "\"{path}\": {m} [[{seg}]] have group or name \"{key}\", {why}: {} \
                             (or give the entry a name = \"...\" and use that)",
                            list.join(", ")
                        ));
                    }
                };
                let Some(t) = items[pick].as_table_mut() else {
                    unreachable!("picked among tables")
                };
                // the array segment consumed the next one too
                let rest = &segs[i + 2..];
                if rest.is_empty() {
                    return Err(format!("\"{path}\": names an entry, not a key in it"));
                }
                return set_in(t, &under(i + 2), &rest.join("."), value, None, made);
            }
            _ => return Err(format!("\"{path}\": \"{seg}\" is not a table")),
        };
    }
    Err(format!("\"{path}\": empty key"))
}

/// The lines (from 1) of the `[[seg]]` headers of a case's source, in file order: entry k of
/// the array is at the k-th (none where the source is unknown).
fn entry_lines(text: Option<&str>, seg: &str) -> Vec<usize> {
    let header = format!("[[{seg}]]");
    text.map_or(Vec::new(), |t| {
        t.lines()
            .enumerate()
            .filter(|(_, l)| l.trim_start().starts_with(&header))
            .map(|(n, _)| n + 1)
            .collect()
    })
}

/// Each line of the TOML `text`: its table's header (as written, spaces and comments removed),
/// that header's occurrence, and the line's key ("" for a header line, a blank or a comment).
pub(super) fn table_lines(text: &str) -> Vec<(String, usize, String)> {
    let mut seen: std::collections::HashMap<String, usize> = Default::default();
    let (mut header, mut nth) = (String::new(), 0);
    (text.lines())
        .map(|l| {
            let t = l.split('#').next().unwrap_or("").trim();
            if t.starts_with('[') {
                header = t.replace(' ', "");
                let n = seen.entry(header.clone()).or_insert(0);
                nth = *n;
                *n += 1;
                return (header.clone(), nth, String::new());
            }
            let key = t.split('=').next().unwrap_or("").trim();
            (header.clone(), nth, key.trim_matches('"').to_string())
        })
        .collect()
}

/// The line of the case file `file` that holds what line `line` of `text` (the file's case
/// re-written with the settings `sets` applied) holds: the same key in the same occurrence of
/// the same table; `None` where the file has no such line or a `--set` gave the key.
pub fn line_in_file(
    text: &str,
    line: usize,
    file: &str,
    sets: &[(String, String)],
) -> Option<usize> {
    let target = table_lines(text).into_iter().nth(line.checked_sub(1)?)?;
    let set_here = sets.iter().any(|(k, _)| {
        let last = k.rsplit('.').next().unwrap_or(k);
        !target.2.is_empty() && last.split('#').next() == Some(target.2.as_str())
    });
    if set_here || target.2.is_empty() && target.0.is_empty() {
        return None;
    }
    (table_lines(file).iter())
        .position(|p| *p == target)
        .map(|i| i + 1)
}

#[cfg(test)]
mod tests {
    use super::{set_path, set_path_making};

    fn doc() -> toml::Table {
        toml::from_str(
            "[[bc]]\ngroup = \"top\"\nuy = -0.2\n[[bc]]\ngroup = \"bottom\"\nuy = 0.0\n[[bc]]\ngroup = \"bottom\"\nname = \"hot\"\ntheta = 20.0\n",
        )
        .unwrap()
    }

    fn value(doc: &toml::Table, i: usize, key: &str) -> toml::Value {
        doc["bc"].as_array().unwrap()[i][key].clone()
    }

    #[test]
    fn a_dotted_path_picks_an_entry_by_group_name_or_number() {
        let mut d = doc();
        set_path(&mut d, "bc.top.uy", toml::Value::Float(-0.3), None).unwrap();
        assert_eq!(value(&d, 0, "uy"), toml::Value::Float(-0.3));
        set_path(&mut d, "bc.hot.theta", toml::Value::Float(40.0), None).unwrap();
        assert_eq!(value(&d, 2, "theta"), toml::Value::Float(40.0));
        set_path(&mut d, "bc.bottom#1.ux", toml::Value::Float(0.0), None).unwrap();
        assert_eq!(value(&d, 1, "ux"), toml::Value::Float(0.0));
        let e = set_path(&mut d, "bc.bottom.uy", toml::Value::Float(1.0), None).unwrap_err();
        assert!(
            e.contains("2 [[bc]] have group or name \"bottom\", say which"),
            "{e}"
        );
        let e = set_path(&mut d, "bc.side.uy", toml::Value::Float(1.0), None).unwrap_err();
        assert!(e.contains("no [[bc]] with group or name \"side\""), "{e}");
        let e = set_path(&mut d, "bc.bottom#0.uy", toml::Value::Float(1.0), None).unwrap_err();
        assert!(e.contains("is no entry number"), "{e}");
    }

    #[test]
    fn a_dotted_path_says_which_table_it_had_to_make() {
        let mut d = doc();
        let v = || toml::Value::Boolean(true);
        // a key of an entry, and a new key in a table that is there: nothing made
        assert_eq!(set_path_making(&mut d, "bc.top.ux", v(), None), Ok(None));
        // a table inside an entry, and one at the top
        assert_eq!(
            set_path_making(&mut d, "bc.hot.friction.forget_slip", v(), None),
            Ok(Some("bc.hot.friction".into()))
        );
        assert_eq!(
            set_path_making(&mut d, "solver.petsc.method", v(), None),
            Ok(Some("solver".into()))
        );
        assert_eq!(
            set_path_making(&mut d, "solver.petsc.options", v(), None),
            Ok(None)
        );
    }
}
