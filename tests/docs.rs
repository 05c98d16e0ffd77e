//! The documents kept true by the code: the README's table of case keys lists exactly the keys
//! the case loader reads, with their defaults, and docs/guide.md gives in full only keys of that
//! table; docs/guide.md's source layout names every file of `src/` and no file that is gone;
//! docs/performance.md's contents list every section, and every link into it names one of its
//! headings; every link of the documents names a file and a heading there, none leaves the
//! repository, and README.md and docs/performance.md stay within 400 lines (issue 58). Each
//! failure says what to add or remove, and where.
use std::collections::BTreeSet;
use std::path::Path;

/// The text of `path`, relative to the repository.
fn read(path: &str) -> String {
    let full = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{}: {e}", full.display()))
}

/// The lines of `text` from the heading `heading` (a whole line) to the next heading of its
/// level or above.
fn section<'t>(text: &'t str, heading: &str) -> Vec<&'t str> {
    let level = heading.chars().take_while(|&c| c == '#').count();
    let mut lines = text.lines().skip_while(|l| *l != heading);
    let first = lines
        .next()
        .unwrap_or_else(|| panic!("no heading `{heading}`"));
    std::iter::once(first)
        .chain(lines.take_while(|l| {
            let hashes = l.chars().take_while(|&c| c == '#').count();
            !(hashes > 0 && hashes <= level && l[hashes..].starts_with(' '))
        }))
        .collect()
}

/// The spans of `text` between backticks.
fn code_spans(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).collect()
}

// The README's table of case keys.

/// The smallest valid case: every key the probes below do not set is at its default.
const BASE: &str = "[grid]\nmodules = [2, 2]\n[load]\nalpha = [1.0]\n";

/// What a key of the case file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Holds {
    /// A value.
    Value,
    /// A table of keys (`[solver]`, `box = { … }`).
    Table,
    /// An array of tables (`[[supports.fix]]`).
    Tables,
}

/// The `--set` that puts `{ zzz = 1 }` at `path` (tables and arrays of tables from the top), a
/// key no table has.
fn unknown_key_at(path: &[(String, Holds)]) -> String {
    fn inline(path: &[(String, Holds)]) -> String {
        match path.split_first() {
            None => "{ zzz = 1 }".into(),
            Some(((name, Holds::Tables), rest)) => format!("{{ {name} = [{}] }}", inline(rest)),
            Some(((name, _), rest)) => format!("{{ {name} = {} }}", inline(rest)),
        }
    }
    let names =
        |p: &[(String, Holds)]| -> Vec<String> { p.iter().map(|(n, _)| n.clone()).collect() };
    match path.iter().position(|(_, h)| *h == Holds::Tables) {
        None => [names(path), vec!["zzz".into()]].concat().join(".") + "=1",
        Some(i) => format!(
            "{}=[{}]",
            names(&path[..=i]).join("."),
            inline(&path[i + 1..])
        ),
    }
}

/// The keys of the table at `path` as the loader reads them: the list serde gives when it
/// refuses an unknown key there. `None` when `path` is not a table.
fn keys_of_table(path: &[(String, Holds)]) -> Option<Vec<String>> {
    let set = unknown_key_at(path);
    let message = tensolve::case::parse_with(BASE, &[set]).err()?.to_string();
    let (_, list) = message.split_once("unknown field `zzz`, expected ")?;
    let list = list.lines().next().unwrap_or("");
    Some(code_spans(list).into_iter().map(String::from).collect())
}

/// A key as the README's table writes it: `supports.fix[i].dofs`.
fn dotted(path: &[(String, Holds)]) -> String {
    let mut parts = Vec::new();
    for (i, (name, holds)) in path.iter().enumerate() {
        let element = *holds == Holds::Tables && i + 1 < path.len();
        parts.push(if element {
            format!("{name}[i]")
        } else {
            name.clone()
        });
    }
    parts.join(".")
}

/// Every key the loader reads under `path`, found by asking each key whether it is a table or
/// an array of tables: dotted, with what it holds and, for tables, its own keys.
fn case_keys(path: &mut Vec<(String, Holds)>, out: &mut Vec<(String, Holds, Vec<String>)>) {
    let keys = keys_of_table(path).expect("the case file is a table");
    for key in keys {
        let holds = [Holds::Table, Holds::Tables]
            .into_iter()
            .find(|&holds| {
                path.push((key.clone(), holds));
                let table = keys_of_table(path).is_some();
                path.pop();
                table
            })
            .unwrap_or(Holds::Value);
        path.push((key, holds));
        let own = match holds {
            Holds::Value => Vec::new(),
            _ => keys_of_table(path).unwrap_or_default(),
        };
        out.push((dotted(path), holds, own));
        if holds != Holds::Value {
            case_keys(path, out);
        }
        path.pop();
    }
}

/// Tables documented by one row of the key table, which names each of their keys.
const ONE_ROW: &[&str] = &[
    "stages",
    "load.point",
    "load.rest_length_change",
    "load.temperature",
    "load.cases",
    "load.combinations",
    "modal.point_mass",
    "supports.fix[i].box",
];

/// Tables documented in a section of their own (whose TOML example names each key), not in
/// the key table.
const OWN_SECTION: &[(&str, &str)] = &[("structure", "### General structures: `[structure]`")];

/// Keys whose default the table describes in words (required, none, a formula, per solver),
/// not as a TOML value.
const DEFAULTS_IN_WORDS: &[&str] = &[
    "grid.modules",
    "prestress.from",
    "bars.strength",
    "bars.inertia",
    "bars.buckling_curve",
    "cables.strength",
    "cables.breaking_load",
    "checks.gamma_r",
    "prestress.member",
    "prestress.force",
    "prestress.targets",
    "prestress.min_cable",
    "prestress.force_density",
    "supports.fix",
    "supports.fix[i].nodes",
    "supports.fix[i].box",
    "load.point",
    "load.rest_length_change",
    "load.temperature",
    "load.cases",
    "load.combinations",
    "stages",
    "modal.point_mass",
    "load.alpha",
    "solver.tolerance",
    "solver.max_iterations",
    "solver.subdomains",
    "solver.dm",
    "solver.macro_degree",
    "solver.residual_tolerance",
    "output.dir",
    "output.amplification",
    "output.figure_alpha",
];

/// An element of each array of tables that the defaults of its keys are checked on.
const ELEMENTS: &[(&str, &str)] = &[("supports.fix", "nodes = [0]")];

/// The rows of the README's key table: (key, default cell, whole row).
fn readme_key_rows(readme: &str) -> Vec<(String, String, String)> {
    let lines = section(readme, "## Case files");
    let start = lines
        .iter()
        .position(|l| l.starts_with("| key | unit | default | allowed |"))
        .expect("the README's key table");
    lines[start + 2..]
        .iter()
        .take_while(|l| l.starts_with('|'))
        .map(|row| {
            let cells: Vec<&str> = row.split('|').map(str::trim).collect();
            let key = cells[1].trim_matches('`').to_string();
            (key, cells[3].to_string(), row.to_string())
        })
        .collect()
}

#[test]
fn readme_key_table_lists_exactly_the_keys_the_loader_reads() {
    let readme = read("README.md");
    let mut keys = Vec::new();
    case_keys(&mut Vec::new(), &mut keys);
    let rows = readme_key_rows(&readme);
    let row_of = |key: &str| rows.iter().find(|(k, _, _)| k == key);
    let mut expected = BTreeSet::new();
    let mut problems = Vec::new();
    for (key, holds, own) in &keys {
        let inside = |outer: &str| {
            key.starts_with(&format!("{outer}.")) || key.starts_with(&format!("{outer}[i]."))
        };
        if ONE_ROW
            .iter()
            .chain(OWN_SECTION.iter().map(|(k, _)| k))
            .any(|k| inside(k))
        {
            continue;
        }
        if let Some((_, heading)) = OWN_SECTION.iter().find(|(k, _)| k == key) {
            let text = section(&readme, heading).join("\n");
            for k in own {
                if !text.contains(&format!("\n{k} = ")) {
                    problems.push(format!(
                        "README's `{heading}` does not show `{k} = …` of [{key}]"
                    ));
                }
            }
            continue;
        }
        if ONE_ROW.contains(&key.as_str()) {
            if let Some((_, _, row)) = row_of(key) {
                for k in own.iter().filter(|k| !row.contains(k.as_str())) {
                    problems.push(format!(
                        "the README's row of `{key}` does not name its key `{k}`"
                    ));
                }
            }
            expected.insert(key.clone());
        } else if *holds != Holds::Table {
            expected.insert(key.clone());
        }
    }
    let listed: BTreeSet<String> = rows.iter().map(|(k, _, _)| k.clone()).collect();
    for key in expected.difference(&listed) {
        problems.push(format!(
            "the loader reads `{key}`: add a row for it to the README's key table"
        ));
    }
    for key in listed.difference(&expected) {
        problems.push(format!(
            "the README's key table has `{key}`, which the loader does not read: remove its row"
        ));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(listed.len() > 50, "found only {} keys", listed.len());
}

/// The TOML value of `text`, if it is one.
fn toml_value(text: &str) -> Option<toml::Value> {
    toml::from_str::<toml::Table>(&format!("v = {text}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
}

#[test]
fn readme_key_table_gives_the_defaults_the_loader_takes() {
    let readme = read("README.md");
    let case = |sets: &[String]| {
        tensolve::case::parse_with(BASE, sets).unwrap_or_else(|e| panic!("{sets:?}: {e}"))
    };
    let mut problems = Vec::new();
    let mut checked = 0;
    for (key, default, _) in readme_key_rows(&readme) {
        let literal = code_spans(&default)
            .first()
            .copied()
            .filter(|s| toml_value(s).is_some());
        let in_words = DEFAULTS_IN_WORDS.contains(&key.as_str());
        let Some(literal) = literal.filter(|_| !in_words) else {
            if !in_words {
                problems.push(format!(
                    "`{key}`: its default `{default}` is not a TOML value; give one, or add the key to DEFAULTS_IN_WORDS in tests/docs.rs"
                ));
            }
            continue;
        };
        // The case without the key, and with it set to the README's default (in an element
        // of its array, or in its table created empty in both).
        let (without, with) = match key.split_once("[i].") {
            Some((array, inner)) => {
                let element = ELEMENTS
                    .iter()
                    .find(|(a, _)| *a == array)
                    .unwrap_or_else(|| panic!("no element of `{array}` in ELEMENTS"))
                    .1;
                (
                    vec![format!("{array}=[{{ {element} }}]")],
                    vec![format!("{array}=[{{ {element}, {inner} = {literal} }}]")],
                )
            }
            None => {
                let parent: Vec<String> = match key.rsplit_once('.') {
                    Some((table, _)) if table.contains('.') => vec![format!("{table}={{}}")],
                    _ => Vec::new(),
                };
                let mut with = parent.clone();
                with.push(format!("{key}={literal}"));
                (parent, with)
            }
        };
        if case(&without) != case(&with) {
            problems.push(format!(
                "`{key}`: the README gives the default `{literal}`, but setting it changes the case"
            ));
        }
        checked += 1;
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(checked > 30, "checked only {checked} defaults");
}

// docs/guide.md's source layout.

/// A bullet of the source layout: its folder (the path its files are named from) and its own
/// text, without its nested bullets.
struct Bullet {
    folder: String,
    text: String,
}

/// The bullets of the guide's source layout. A bullet that opens with a folder (`` `src/linalg/` ``,
/// nested: `` `latin/` ``, from its parent's) names its files from that folder; any other names
/// them from its parent's (the top: the repository).
fn layout_bullets(guide: &str) -> Vec<Bullet> {
    let mut bullets: Vec<Bullet> = Vec::new();
    let mut parents: Vec<(usize, String)> = Vec::new(); // (indent, folder)
    for line in section(guide, "## Source layout") {
        let indent = line.len() - line.trim_start().len();
        let Some(text) = line.trim_start().strip_prefix("* ") else {
            if let Some(b) = bullets.last_mut() {
                b.text.push(' ');
                b.text.push_str(line.trim());
            }
            continue;
        };
        while parents.last().is_some_and(|(i, _)| *i >= indent) {
            parents.pop();
        }
        let parent = parents.last().map_or(String::new(), |(_, f)| f.clone());
        let folder = match text.strip_prefix('`').and_then(|t| t.split('`').next()) {
            Some(first) if first.ends_with('/') => format!("{parent}{first}"),
            _ => parent,
        };
        parents.push((indent, folder.clone()));
        bullets.push(Bullet {
            folder,
            text: text.to_string(),
        });
    }
    bullets
}

/// Whether `text` names `path` as a whole word (not as the end of a longer path).
fn names(text: &str, path: &str) -> bool {
    let word = |c: char| c.is_alphanumeric() || c == '_' || c == '/';
    text.match_indices(path).any(|(at, _)| {
        !text[..at].chars().next_back().is_some_and(word)
            && !text[at + path.len()..]
                .chars()
                .next()
                .is_some_and(|c| c.is_alphanumeric() || c == '_')
    })
}

/// Every `.rs` file under `dir`, by its path from the repository.
fn rust_files(root: &Path, dir: &str, out: &mut Vec<String>) {
    for entry in std::fs::read_dir(root.join(dir)).unwrap() {
        let entry = entry.unwrap();
        let path = format!("{dir}/{}", entry.file_name().to_string_lossy());
        if entry.file_type().unwrap().is_dir() {
            rust_files(root, &path, out);
        } else if path.ends_with(".rs") {
            out.push(path);
        }
    }
}

/// When files move, this test names each one to add to (or remove from) the guide's "Source
/// layout": a file goes in the bullet of its folder, by its path from that folder
/// (`src/solvers/` names `newton/mod.rs`); a file whose folder has no bullet goes anywhere in
/// the layout by its whole path.
#[test]
fn guide_source_layout_names_every_source_file() {
    let guide = read("docs/guide.md");
    let whole = section(&guide, "## Source layout").join("\n");
    let bullets = layout_bullets(&guide);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(root, "src", &mut files);
    files.sort();
    let mut problems = Vec::new();
    for file in &files {
        let bullet = bullets
            .iter()
            .filter(|b| !b.folder.is_empty() && file.starts_with(&b.folder))
            .max_by_key(|b| b.folder.len());
        let named = match bullet {
            Some(b) => names(&b.text, &file[b.folder.len()..]),
            None => names(&whole, file),
        };
        if !named {
            problems.push(match bullet {
                Some(b) => format!(
                    "{file}: not named in docs/guide.md's Source layout; add `{}` to the bullet of `{}`",
                    &file[b.folder.len()..],
                    b.folder
                ),
                None => format!("{file}: not named in docs/guide.md's Source layout; add it by its whole path"),
            });
        }
    }
    // The other way: every file a bullet names is there.
    for b in &bullets {
        let words = b
            .text
            .split(|c: char| !(c.is_alphanumeric() || "_./".contains(c)));
        for word in words.filter(|w| w.ends_with(".rs")) {
            let there = [
                format!("{}{word}", b.folder),
                word.to_string(),
                format!("src/{word}"),
            ]
            .iter()
            .any(|p| root.join(p).is_file());
            if !there {
                problems.push(format!(
                    "docs/guide.md's Source layout names `{word}` (bullet of `{}`), which is not there: remove or rename it",
                    b.folder
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

// docs/performance.md's contents and the links into it.

/// The anchor GitHub gives a heading: lower case, spaces to hyphens, punctuation dropped.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            '-' | '_' => Some(c),
            // Combining marks (k̄) stay, as letters do.
            c if c.is_alphanumeric() || ('\u{300}'..='\u{36f}').contains(&c) => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of the `##` and `###` headings of `text`, outside code blocks.
fn heading_anchors(text: &str) -> Vec<(String, String)> {
    let mut fenced = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.starts_with("```") {
            fenced = !fenced;
        }
        if fenced {
            continue;
        }
        if let Some(h) = line
            .strip_prefix("## ")
            .or_else(|| line.strip_prefix("### "))
        {
            out.push((h.to_string(), anchor(h)));
        }
    }
    out
}

/// The targets of the links `](#…)` in `text` (`prefix`: `](performance.md#` and the like).
fn link_targets<'t>(text: &'t str, prefix: &str) -> Vec<&'t str> {
    text.split(prefix)
        .skip(1)
        .filter_map(|rest| rest.split(')').next())
        .collect()
}

#[test]
fn performance_contents_list_every_section() {
    let text = read("docs/performance.md");
    let contents: String = text
        .lines()
        .take_while(|l| !l.starts_with("## "))
        .collect::<Vec<_>>()
        .join("\n");
    let listed: BTreeSet<&str> = link_targets(&contents, "](#").into_iter().collect();
    let headings = heading_anchors(&text);
    let mut problems = Vec::new();
    for (heading, a) in &headings {
        if !listed.contains(a.as_str()) {
            problems.push(format!(
                "docs/performance.md's contents do not list `{heading}`: add [{heading}](#{a})"
            ));
        }
    }
    for a in &listed {
        if !headings.iter().any(|(_, h)| h == a) {
            problems.push(format!(
                "docs/performance.md's contents link #{a}, which no heading has"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn links_into_performance_name_its_headings() {
    let headings = heading_anchors(&read("docs/performance.md"));
    let mut problems = Vec::new();
    for (file, prefix) in [
        ("README.md", "](docs/performance.md#"),
        ("docs/guide.md", "](performance.md#"),
        ("docs/method.md", "](performance.md#"),
        ("docs/performance.md", "](#"),
    ] {
        for a in link_targets(&read(file), prefix) {
            if !headings.iter().any(|(_, h)| h == a) {
                problems.push(format!(
                    "{file} links performance.md#{a}, which no heading has"
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// N-D5 (issue 57): the README's key table says which `prestress.from` each of the prestress
/// source's keys belongs to, as the loader takes them: `member` and `force` were "required
/// with `from`" while `from = "design"` refuses them.
#[test]
fn readme_says_which_prestress_source_each_key_belongs_to() {
    let readme = read("README.md");
    let rows = readme_key_rows(&readme);
    let tables = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tower3q");
    let sources = ["self-stress", "design", "force-density"];
    let keys = [
        ("member", "0"),
        ("force", "1000.0"),
        ("targets", "{ bars0 = -5000.0 }"),
        ("min_cable", "10.0"),
        ("force_density", "{ bars0 = -10.0 }"),
    ];
    for (key, value) in keys {
        let belongs: Vec<&str> = sources
            .iter()
            .copied()
            .filter(|from| {
                let text = format!(
                    "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n\
                     [[supports.fix]]\nnodes = [0, 1, 2, 3]\n[prestress]\nfrom = \"{from}\"\n\
                     {key} = {value}\n[load]\nalpha = [1.0]\n"
                );
                let refused = match tensolve::case::parse_in(&text, &tables) {
                    Ok(_) => false,
                    Err(e) => {
                        e.to_string().contains(&format!("prestress.{key}"))
                            && e.to_string().contains("it belongs to")
                    }
                };
                !refused
            })
            .collect();
        assert_eq!(belongs.len(), 1, "prestress.{key}: taken with {belongs:?}");
        let (_, default, _) = rows
            .iter()
            .find(|(k, _, _)| *k == format!("prestress.{key}"))
            .unwrap_or_else(|| panic!("no README row for prestress.{key}"));
        assert!(
            default.contains(&format!("from = \"{}\"", belongs[0])),
            "the README's default of prestress.{key} is `{default}`: it belongs to \
             `from = \"{}\"`",
            belongs[0]
        );
        for other in sources.iter().filter(|s| **s != belongs[0]) {
            assert!(
                !default.contains(&format!("required with `from = \"{other}\"`")),
                "prestress.{key}: `{default}`"
            );
        }
        assert!(
            !default.ends_with("with `from`"),
            "prestress.{key}: `{default}`"
        );
    }
}

// The documents as references (issue 58): short, inside the repository, their links whole.

/// README.md and every Markdown file under docs/, by their paths from the repository.
fn markdown_files() -> Vec<String> {
    fn walk(root: &Path, dir: &str, out: &mut Vec<String>) {
        for entry in std::fs::read_dir(root.join(dir)).unwrap() {
            let entry = entry.unwrap();
            let path = format!("{dir}/{}", entry.file_name().to_string_lossy());
            if entry.file_type().unwrap().is_dir() {
                walk(root, &path, out);
            } else if path.ends_with(".md") {
                out.push(path);
            }
        }
    }
    let mut files = vec!["README.md".to_string()];
    walk(Path::new(env!("CARGO_MANIFEST_DIR")), "docs", &mut files);
    files.sort();
    files
}

/// The text of `text` outside fenced code blocks, and the lines inside them.
fn prose_and_code(text: &str) -> (String, Vec<&str>) {
    let (mut prose, mut code, mut fenced) = (String::new(), Vec::new(), false);
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if fenced {
            code.push(line);
        } else {
            prose.push_str(line);
            prose.push('\n');
        }
    }
    (prose, code)
}

/// The code spans of `prose` as Markdown reads them: a run of n backticks opens one, the next
/// run of exactly n closes it (a span may go on over a line end).
fn markdown_code_spans(prose: &str) -> Vec<String> {
    let bytes = prose.as_bytes();
    let run_at = |i: usize| bytes[i..].iter().take_while(|&&b| b == b'`').count();
    let (mut spans, mut i) = (Vec::new(), 0);
    while i < bytes.len() {
        if bytes[i] != b'`' {
            i += 1;
            continue;
        }
        let n = run_at(i);
        let start = i + n;
        let mut j = start;
        let mut close = None;
        while j < bytes.len() {
            if bytes[j] == b'`' {
                let m = run_at(j);
                if m == n {
                    close = Some(j);
                    break;
                }
                j += m;
            } else {
                j += 1;
            }
        }
        match close {
            Some(end) => {
                spans.push(prose[start..end].replace('\n', " ").trim().to_string());
                i = end + n;
            }
            None => i = start,
        }
    }
    spans
}

/// The targets of the inline links and images `](target)` of `prose`.
fn markdown_link_targets(prose: &str) -> Vec<&str> {
    prose
        .split("](")
        .skip(1)
        .filter_map(|rest| rest.split([')', ' ']).next())
        .collect()
}

/// Absolute paths a document may name: the machine's tools and kernel interfaces
/// (`/usr/bin/time`, `/proc/meminfo`, `/dev/zero`), which are no file of a checkout.
const SYSTEM_PATHS: &[&str] = &["/usr/", "/proc", "/sys", "/dev/"];

/// Whether `word`, a path a document names, lies outside the repository: above it (`../`),
/// in a home (`~/`) or absolute, other than the machine's own.
fn outside_the_repository(word: &str) -> bool {
    let word = word.trim_matches(|c: char| "'\"(),;:".contains(c));
    word.starts_with("../")
        || word.starts_with("~/")
        || (word.starts_with('/')
            && word.len() > 1
            && !SYSTEM_PATHS.iter().any(|p| word.starts_with(p)))
}

/// Issue 58: "No link outside the repository." Every link of the README and of docs/ stays in
/// the repository (no address, no absolute path, no `..` that climbs out of it), and no path a
/// document names in backquotes or in a code block starts with `../` or is absolute (a script
/// of another checkout, `../shared/tools/…`, is described, not named).
#[test]
fn no_link_or_path_leaves_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut problems = Vec::new();
    for file in markdown_files() {
        let text = read(&file);
        let (prose, code) = prose_and_code(&text);
        let depth = file.matches('/').count();
        for target in markdown_link_targets(&prose) {
            let path = target.split('#').next().unwrap_or("");
            let climbs = path
                .split('/')
                .try_fold(depth as i64, |d, part| match part {
                    ".." if d == 0 => None,
                    ".." => Some(d - 1),
                    "" | "." => Some(d),
                    _ => Some(d + 1),
                })
                .is_none();
            if target.contains("://")
                || target.starts_with("mailto:")
                || path.starts_with('/')
                || climbs
            {
                problems.push(format!("{file}: the link ({target}) leaves the repository"));
            }
        }
        let words = markdown_code_spans(&prose)
            .into_iter()
            .filter_map(|span| span.split_whitespace().next().map(String::from))
            .chain(
                code.iter()
                    .flat_map(|l| l.split_whitespace())
                    .map(String::from),
            );
        for word in words.filter(|w| outside_the_repository(w)) {
            problems.push(format!(
                "{file}: `{word}` is a path outside the repository: describe what it is instead"
            ));
        }
    }
    assert!(root.join("docs").is_dir());
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Issue 58: the README is a front door and docs/performance.md the current state, each at
/// most 400 lines; the long tables go to docs/guide.md, the dated history to docs/journal/.
#[test]
fn the_readme_and_performance_are_at_most_400_lines() {
    let mut problems = Vec::new();
    for (file, elsewhere) in [
        ("README.md", "docs/guide.md"),
        ("docs/performance.md", "docs/journal/"),
    ] {
        let lines = read(file).lines().count();
        if lines > 400 {
            problems.push(format!(
                "{file} has {lines} lines, more than 400: move what is long to {elsewhere}"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// GitHub's anchor of every heading of `text` (any level, outside code blocks), a repeated one
/// numbered as GitHub numbers it (`-1`, `-2`, …).
fn all_heading_anchors(text: &str) -> BTreeSet<String> {
    let (prose, _) = prose_and_code(text);
    let mut seen: Vec<String> = Vec::new();
    let mut out = BTreeSet::new();
    for line in prose.lines() {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if !(1..=6).contains(&hashes) || !line[hashes..].starts_with(' ') {
            continue;
        }
        let a = anchor(&line[hashes + 1..]);
        let n = seen.iter().filter(|s| **s == a).count();
        out.insert(if n == 0 {
            a.clone()
        } else {
            format!("{a}-{n}")
        });
        seen.push(a);
    }
    out
}

/// Every relative link of the README and of docs/ names a file of the repository, and, with
/// `#…`, one of that Markdown file's headings: a section that moved (to docs/guide.md, to
/// docs/journal/) takes its links with it.
#[test]
fn every_link_names_a_file_and_a_heading_there() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut problems = Vec::new();
    let mut checked = 0;
    for file in markdown_files() {
        let (prose, _) = prose_and_code(&read(&file));
        let dir = Path::new(&file).parent().unwrap_or(Path::new(""));
        for target in markdown_link_targets(&prose) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue; // the test above refuses these
            }
            let (path, fragment) = target.split_once('#').unwrap_or((target, ""));
            let linked = if path.is_empty() {
                root.join(&file)
            } else {
                root.join(dir).join(path)
            };
            checked += 1;
            if !linked.exists() {
                problems.push(format!("{file}: ({target}) names no file"));
                continue;
            }
            if fragment.is_empty() {
                continue;
            }
            let text = std::fs::read_to_string(&linked).unwrap_or_default();
            if !all_heading_anchors(&text).contains(fragment) {
                problems.push(format!(
                    "{file}: ({target}) names no heading of {}",
                    linked.display()
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(checked > 100, "checked only {checked} links");
}

/// The guide's "Case keys in detail" gives in full the keys whose README cell is short, by
/// the README's own names: every key it names is a row of the README's key table, and every
/// row that sends the reader there (`[more](docs/guide.md#keys-of-…)`) has its key in the
/// section it names.
#[test]
fn guide_key_details_match_the_readme_key_table() {
    let readme = read("README.md");
    let guide = read("docs/guide.md");
    let rows = readme_key_rows(&readme);
    let mut problems = Vec::new();
    let details = section(&guide, "## Case keys in detail");
    let mut by_section: Vec<(String, String)> = Vec::new(); // (anchor, key)
    let mut current = String::new();
    for line in &details {
        if let Some(h) = line.strip_prefix("### ") {
            current = anchor(h);
        } else if let Some(rest) = line.strip_prefix("| `") {
            let key = rest.split('`').next().unwrap_or("").to_string();
            if !rows.iter().any(|(k, _, _)| *k == key) {
                problems.push(format!(
                    "docs/guide.md's Case keys in detail has `{key}`, which the README's key table does not"
                ));
            }
            by_section.push((current.clone(), key));
        }
    }
    for (key, _, row) in &rows {
        for a in link_targets(row, "](docs/guide.md#") {
            if a.starts_with("keys-of-") && !by_section.iter().any(|(s, k)| s == a && k == key) {
                problems.push(format!(
                    "the README's row of `{key}` links docs/guide.md#{a}, whose table has no row for it"
                ));
            }
        }
    }
    assert!(
        by_section.len() > 30,
        "found only {} keys",
        by_section.len()
    );
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
