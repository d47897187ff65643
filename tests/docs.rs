//! The manual held to the code: README.md and the book under `docs/src/` (an mdBook).
//!
//! - every relative link and `#anchor` in them resolves (this runs in `cargo test`, so it holds
//!   without mdbook installed), and every chapter is listed in `docs/src/SUMMARY.md`;
//! - every ```` ```rust ```` block in them is one of the examples at the end of this file, which
//!   compile and run here: the examples cannot drift from the API;
//! - the scenes chapter's key tables are exactly the keys the scene parser accepts, and their
//!   defaults, ranges and choices are the parser's (`every_documented_scene_key_*`);
//! - README.md stays a five-minute read: at most 250 lines, no dates, no commit hashes.

use pelage::scene::Scene;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// README.md and every chapter of the book.
fn markdown_files() -> Vec<PathBuf> {
    let mut files = vec![root().join("README.md")];
    let mut chapters: Vec<PathBuf> = std::fs::read_dir(root().join("docs/src"))
        .expect("docs/src")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    chapters.sort();
    files.extend(chapters);
    files
}

/// The fenced code blocks of a markdown text: (info string, body, first line number).
fn code_blocks(text: &str) -> Vec<(String, String, usize)> {
    let mut blocks = Vec::new();
    let mut open: Option<(String, String, usize)> = None;
    for (n, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(info) = trimmed.strip_prefix("```") {
            match open.take() {
                Some(block) => blocks.push(block),
                None => open = Some((info.trim().to_string(), String::new(), n + 1)),
            }
        } else if let Some((_, body, _)) = open.as_mut() {
            body.push_str(line);
            body.push('\n');
        }
    }
    assert!(open.is_none(), "an unclosed code block");
    blocks
}

/// The lines outside fenced code blocks, with their numbers.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut fenced = false;
    let mut lines = Vec::new();
    for (n, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced {
            lines.push((n + 1, line));
        }
    }
    lines
}

/// The id mdBook (and GitHub) give a heading: lower case, letters, digits, `-` and `_` kept,
/// spaces as `-`, the rest dropped.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .chars()
        .flat_map(char::to_lowercase)
        .filter_map(|c| match c {
            c if c.is_alphanumeric() || c == '_' || c == '-' => Some(c),
            c if c.is_whitespace() => Some('-'),
            _ => None,
        })
        .collect()
}

fn anchors(text: &str) -> BTreeSet<String> {
    prose_lines(text)
        .into_iter()
        .filter_map(|(_, l)| l.strip_prefix('#'))
        .map(|h| anchor(h.trim_start_matches('#')))
        .collect()
}

/// Every markdown link target in the prose of `text`: `[x](target)` and `![x](target)`.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (n, line) in prose_lines(text) {
        // Inline code spans hold examples, not links.
        let prose: String = line
            .split('`')
            .enumerate()
            .filter(|(k, _)| k % 2 == 0)
            .map(|(_, s)| s)
            .collect::<Vec<_>>()
            .join(" ");
        let mut rest = prose.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let end = after.find(')').unwrap_or(after.len());
            let target = after[..end].split_whitespace().next().unwrap_or("");
            found.push((n, target.to_string()));
            rest = &after[end..];
        }
    }
    found
}

#[test]
fn every_relative_link_and_anchor_resolves() {
    let mut broken = Vec::new();
    for file in markdown_files() {
        let text = read(&file);
        for (line, target) in links(&text) {
            if target.starts_with("http://")
                || target.starts_with("https://")
                || target.starts_with("mailto:")
            {
                continue;
            }
            let (path, fragment) = target.split_once('#').unwrap_or((&target, ""));
            let resolved = if path.is_empty() {
                file.clone()
            } else {
                file.parent().expect("folder").join(path)
            };
            let name = format!("{}:{line}: {target}", file.display());
            if target.contains("shared/") {
                broken.push(format!("{name} (points outside the repository)"));
            } else if !resolved.exists() {
                broken.push(format!("{name} (no such file)"));
            } else if !fragment.is_empty()
                && resolved.extension().is_some_and(|e| e == "md")
                && !anchors(&read(&resolved)).contains(fragment)
            {
                broken.push(format!("{name} (no such heading)"));
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn every_chapter_is_in_the_summary() {
    let summary = read(&root().join("docs/src/SUMMARY.md"));
    let listed: BTreeSet<String> = links(&summary).into_iter().map(|(_, t)| t).collect();
    for file in markdown_files().iter().skip(1) {
        let name = file
            .file_name()
            .expect("name")
            .to_string_lossy()
            .to_string();
        assert!(
            name == "SUMMARY.md" || listed.contains(&name),
            "docs/src/{name} is not listed in docs/src/SUMMARY.md"
        );
    }
    let book = read(&root().join("docs/book.toml"));
    assert!(book.contains("src = \"src\""), "{book}");
}

#[test]
fn the_readme_is_short_and_has_no_diary() {
    let readme = read(&root().join("README.md"));
    let lines = readme.lines().count();
    assert!(lines <= 250, "README.md has {lines} lines, more than 250");
    let words: Vec<&str> = readme.split_whitespace().collect();
    for (k, word) in words.iter().enumerate() {
        let w = word.trim_matches(|c: char| !c.is_ascii_alphanumeric() && c != '-');
        let b = w.as_bytes();
        let is_date = b.len() == 10
            && b[..4].iter().all(u8::is_ascii_digit)
            && b.starts_with(b"20")
            && b[4] == b'-'
            && b[7] == b'-';
        assert!(!is_date, "README.md holds a date: {word}");
        let hexish = w.len() >= 7
            && w.bytes().all(|c| c.is_ascii_hexdigit())
            && w.bytes().any(|c| c.is_ascii_digit());
        if k > 0 && ["with", "build", "commit"].contains(&words[k - 1]) {
            assert!(!hexish, "README.md names a commit: {} {word}", words[k - 1]);
        }
    }
    assert!(
        !readme.contains("shared/"),
        "README.md points outside the repository"
    );
    assert!(
        words
            .join(" ")
            .contains("Real-Time Fur Modeling with Simulation of Physical Effects"),
        "README.md names the thesis"
    );
    for line in readme
        .lines()
        .filter(|l| l.contains("cargo install --path ."))
    {
        assert!(line.contains("--locked"), "{line}");
    }
    // Completions are written into folders a fresh home lacks: a `mkdir -p` above makes them.
    let lines: Vec<&str> = readme.lines().collect();
    for (k, line) in lines.iter().enumerate() {
        let Some(target) = line
            .split_once("pelage completions")
            .and_then(|(_, rest)| rest.split_once('>'))
            .and_then(|(_, path)| path.split_whitespace().next())
        else {
            continue;
        };
        let folder = target.rsplit_once('/').map_or("", |(f, _)| f);
        assert!(
            lines[..k]
                .iter()
                .any(|l| l.contains("mkdir -p") && l.contains(folder)),
            "README.md: {line}: no `mkdir -p {folder}` before it"
        );
    }
}

/// The examples of this file, by name: the text between `// example: NAME` and
/// `// end of example`, indentation removed.
fn examples() -> BTreeMap<String, String> {
    let source = include_str!("docs.rs");
    let mut examples = BTreeMap::new();
    let mut current: Option<(String, Vec<&str>)> = None;
    for line in source.lines() {
        let t = line.trim();
        if let Some(name) = t.strip_prefix("// example: ") {
            current = Some((name.to_string(), Vec::new()));
        } else if t == "// end of example" {
            let (name, body) = current.take().expect("an open example");
            let indent = body
                .iter()
                .filter(|l| !l.trim().is_empty())
                .map(|l| l.len() - l.trim_start().len())
                .min()
                .unwrap_or(0);
            let text: String = body
                .iter()
                .map(|l| format!("{}\n", l.get(indent..).unwrap_or("")))
                .collect();
            examples.insert(name, text);
        } else if let Some((_, body)) = current.as_mut() {
            body.push(line);
        }
    }
    examples
}

#[test]
fn every_rust_block_is_a_checked_example_and_every_block_names_its_language() {
    let examples = examples();
    assert!(!examples.is_empty());
    let mut problems = Vec::new();
    for file in markdown_files() {
        for (info, body, line) in code_blocks(&read(&file)) {
            let at = format!("{}:{line}", file.display());
            if info.is_empty() {
                problems.push(format!(
                    "{at}: a code block without a language (text, sh, toml…)"
                ));
            } else if info == "rust" && !examples.values().any(|e| *e == body) {
                problems.push(format!(
                    "{at}: a rust block that is not an example of tests/docs.rs:\n{body}"
                ));
            } else if info.starts_with("rust") && info != "rust" {
                problems.push(format!(
                    "{at}: `{info}`: rust blocks are checked, mark others text"
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

// ---------------------------------------------------------------------------------------------
// The scenes chapter against the scene parser.

/// One row of a key table in docs/src/scenes.md.
#[derive(Debug)]
struct KeyRow {
    key: String,
    default: String,
    range: String,
    meaning: String,
}

fn key_rows() -> Vec<KeyRow> {
    let text = read(&root().join("docs/src/scenes.md"));
    let mut rows = Vec::new();
    let mut in_table = false;
    for (_, line) in prose_lines(&text) {
        if line.starts_with("| key | default | range |") {
            in_table = true;
            continue;
        }
        if !line.starts_with('|') {
            in_table = false;
            continue;
        }
        if !in_table || line.starts_with("| ---") {
            continue;
        }
        let cells: Vec<String> = line
            .trim()
            .trim_matches('|')
            .split(" | ")
            .map(|c| c.trim().to_string())
            .collect();
        assert_eq!(cells.len(), 4, "{line}");
        let key = cells[0].trim_matches('`').to_string();
        rows.push(KeyRow {
            key,
            default: cells[1].clone(),
            range: cells[2].clone(),
            meaning: cells[3].clone(),
        });
    }
    assert!(
        rows.len() > 80,
        "the scenes chapter lists {} keys",
        rows.len()
    );
    rows
}

/// The backticked words of a table cell.
fn ticked(cell: &str) -> Vec<&str> {
    cell.split('`').skip(1).step_by(2).collect()
}

/// The section of a documented key (`spots[].colour` → `spots`, `seed` → ``) and its name.
fn split_key(key: &str) -> (String, String) {
    let plain = key.replace("[]", "");
    match plain.rsplit_once('.') {
        Some((section, name)) => (section.to_string(), name.to_string()),
        None => (String::new(), plain),
    }
}

/// Scene text that opens `section` (with what it needs to be valid) and sets `lines`.
fn snippet(section: &str, kind: Option<&str>, lines: &str) -> String {
    let mut text = match section {
        "" => String::new(),
        "spots" | "stripes" => format!("[[{section}]]\n"),
        s => format!("[{s}]\n"),
    };
    if let Some(kind) = kind {
        text.push_str(&format!("kind = \"{kind}\"\n"));
    }
    if section == "motion" && !lines.starts_with("path") {
        text.push_str("path = [[0.0, 0.0, 0.0, 0.0]]\n");
    }
    // A glTF mesh needs its path (the file is not read while parsing).
    if section == "mesh" && kind == Some("gltf") && !lines.starts_with("path") {
        text.push_str("path = \"model.glb\"\n");
    }
    text.push_str(lines);
    text.push('\n');
    // `[animation]` plays a glTF model's clip.
    if section == "animation" {
        text.push_str("[mesh]\nkind = \"gltf\"\npath = \"model.glb\"\n");
    }
    text
}

fn parse(text: &str) -> Result<Scene, String> {
    Scene::parse(text, "docs-test.toml", Path::new(".")).map_err(|e| e.to_string())
}

/// The names serde lists after "expected" in a refusal: the keys or choices the parser knows.
fn expected_names(message: &str) -> BTreeSet<String> {
    let (_, list) = message
        .split_once("expected")
        .unwrap_or_else(|| panic!("no list in: {message}"));
    ticked(list).into_iter().map(str::to_string).collect()
}

/// The kind a row's key needs (`kind = "light"` in its meaning cell).
fn kind_of(row: &KeyRow) -> Option<&str> {
    let at = row.meaning.find("kind = \"")?;
    let rest = &row.meaning[at + 8..];
    Some(&rest[..rest.find('"')?])
}

#[test]
fn every_documented_scene_key_is_the_parsers_and_no_other() {
    let rows = key_rows();
    // section → the names documented in it: keys, and the sub-sections below it.
    let mut documented: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for row in &rows {
        let (section, name) = split_key(&row.key);
        assert!(
            documented.entry(section.clone()).or_default().insert(name),
            "{} is listed twice",
            row.key
        );
        let mut parent = section;
        while !parent.is_empty() {
            let (up, child) = match parent.rsplit_once('.') {
                Some((u, c)) => (u.to_string(), c.to_string()),
                None => (String::new(), parent.clone()),
            };
            documented.entry(up.clone()).or_default().insert(child);
            parent = up;
        }
    }
    for (section, names) in &documented {
        let err = parse(&snippet(section, None, "zz_not_a_key = 0"))
            .expect_err("an unknown key is refused");
        let known: BTreeSet<String> = expected_names(&err)
            .into_iter()
            .filter(|n| n != "zz_not_a_key")
            .collect();
        let missing: Vec<_> = known.difference(names).collect();
        let extra: Vec<_> = names.difference(&known).collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "[{section}]: the parser accepts {missing:?} that docs/src/scenes.md does not list, \
             and the chapter lists {extra:?} that the parser refuses"
        );
    }
}

#[test]
fn every_documented_scene_key_has_the_parsers_default_range_and_choices() {
    let mut checked = 0;
    for row in key_rows() {
        let (section, name) = split_key(&row.key);
        let kind = kind_of(&row).filter(|_| name != "kind");
        let set = |value: &str| parse(&snippet(&section, kind, &format!("{name} = {value}")));
        let at = format!("{} (docs/src/scenes.md)", row.key);
        // A default written as one value: setting it changes nothing.
        if let [default] = ticked(&row.default)[..]
            && row.default == format!("`{default}`")
        {
            let base = parse(&snippet(&section, kind, "")).unwrap_or_else(|e| panic!("{at}: {e}"));
            let given = set(default).unwrap_or_else(|e| panic!("{at} = {default}: {e}"));
            assert_eq!(given, base, "{at}: the default is not {default}");
            checked += 1;
        }
        // A range written as `a..=b`: both ends accepted, beyond them refused.
        if let [range] = ticked(&row.range)[..]
            && let Some((lo, hi)) = range.split_once("..=")
        {
            assert_eq!(row.range, format!("`{range}`"), "{at}");
            let float = lo.contains('.') || hi.contains('.');
            let step = |v: &str, sign: f64| -> String {
                let x: f64 = v.parse().unwrap_or_else(|_| panic!("{at}: {v}"));
                if float {
                    format!("{:?}", x + sign * x.abs().max(1.0))
                } else {
                    format!("{}", x as i64 + sign as i64)
                }
            };
            for v in [lo, hi] {
                set(v).unwrap_or_else(|e| panic!("{at} = {v} is refused: {e}"));
            }
            for v in [step(lo, -1.0), step(hi, 1.0)] {
                assert!(set(&v).is_err(), "{at} = {v} is accepted");
            }
            checked += 1;
        }
        // Choices written as quoted strings: exactly the parser's.
        let choices: BTreeSet<String> = ticked(&row.range)
            .into_iter()
            .filter(|c| c.starts_with('"'))
            .map(|c| c.trim_matches('"').to_string())
            .collect();
        if !choices.is_empty() {
            for c in &choices {
                // A choice may need other keys (`mesh.kind = "obj"` needs a path), never more.
                if let Err(e) = set(&format!("\"{c}\"")) {
                    assert!(!e.contains("unknown variant"), "{at} = \"{c}\": {e}");
                }
            }
            let err = set("\"zz_not_a_choice\"").expect_err("an unknown choice");
            assert_eq!(expected_names(&err), choices, "{at}");
            checked += 1;
        }
    }
    assert!(checked > 80, "only {checked} checks");
}

#[test]
fn every_scene_example_in_the_manual_parses() {
    let mut parsed = 0;
    for file in [root().join("README.md"), root().join("docs/src/scenes.md")] {
        for (info, body, line) in code_blocks(&read(&file)) {
            if info == "toml" {
                parse(&body).unwrap_or_else(|e| panic!("{}:{line}: {e}", file.display()));
                parsed += 1;
            }
        }
    }
    assert!(parsed >= 4, "{parsed} examples");
}

#[test]
fn every_dotted_sweep_parameter_in_the_manual_is_a_scene_key() {
    let keys: BTreeSet<String> = key_rows().into_iter().map(|r| r.key).collect();
    for file in markdown_files() {
        let text = read(&file);
        for part in text.split("--param ").skip(1) {
            let name: String = part
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == '.')
                .collect();
            if name.contains('.') {
                assert!(keys.contains(&name), "{}: --param {name}", file.display());
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The examples the README and the book show, compiled and run here.

#[test]
fn the_whole_frame_example_renders() -> Result<(), Box<dyn std::error::Error>> {
    // example: whole frame
    use pelage::render::PreparedScene;
    use pelage::scene::Scene;

    let mut scene = Scene::embedded_default()?; // the furred torus; or Scene::load(path)?
    scene.image.width = 320;
    scene.image.height = 240;
    let prepared = PreparedScene::new(&scene)?; // builds the mesh, bakes the fur
    let frame = prepared.render_at(0.0, 64)?; // time 0 s, 64-pixel tiles
    assert_eq!(frame.rgba8.len(), 320 * 240 * 4); // RGBA8, row 0 at the top
    let path = std::env::temp_dir().join("torus.png");
    pelage::output::write_png(&path, frame.width, frame.height, &frame.rgba8)?;
    // end of example
    Ok(())
}

#[test]
fn the_shading_term_example_holds() {
    // example: shading term
    use pelage::glam::Vec3;
    use pelage::shading::{BANKS_EXPONENT, kajiya_kay_diffuse};

    // Eq. 2.5 with Banks's exponent: the sine between strand tangent and light, raised to 4.8.
    let tangent = Vec3::new(0.5, 0.0, 0.866);
    let diffuse = kajiya_kay_diffuse(tangent, Vec3::Z, BANKS_EXPONENT);
    let sine = (1.0 - 0.866f32 * 0.866 / tangent.length_squared()).sqrt();
    assert!((diffuse - sine.powf(4.8)).abs() < 1e-5);
    // end of example
}
