//! The README's claims that go stale as the code moves on (issue 41), checked against the
//! repository by reading files only: the README stays within 450 lines; every path in its
//! *How it works* section and code map exists; neither it nor the crate docs say that every
//! engine gives the same mesh (the narrow band can miss blobs beyond its band, see
//! docs/reference/recon.md, *Engines*); and every relative link of README.md and docs/ resolves,
//! anchors included.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

const MAX_README_LINES: usize = 450;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(relative: &str) -> String {
    let path = root().join(relative);
    fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The text of the `##`/`###` section headed `title` up to the next heading of its level or
/// above, outside fenced code blocks.
fn section<'a>(markdown: &'a str, title: &str) -> &'a str {
    let mut start = None;
    let mut level = 0;
    let mut offset = 0;
    let mut fenced = false;
    for line in markdown.split_inclusive('\n') {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        }
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if !fenced && hashes > 0 && line[hashes..].starts_with(' ') {
            match start {
                None if line[hashes..].trim() == title => {
                    start = Some(offset + line.len());
                    level = hashes;
                }
                Some(s) if hashes <= level => return &markdown[s..offset],
                _ => {}
            }
        }
        offset += line.len();
    }
    let s = start.unwrap_or_else(|| panic!("README.md has no section '{title}'"));
    &markdown[s..]
}

/// The `code spans` of a piece of Markdown.
fn code_spans(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).collect()
}

/// A code span that names a file or folder of the repository: `src/`, `mesh/post/`,
/// `narrow_band.rs`; not `<format>_read.rs`, `Config` or `--raw`.
fn is_path(span: &str) -> bool {
    !span.is_empty()
        && (span.ends_with('/') || span.ends_with(".rs") || span.ends_with(".md"))
        && span
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "/._-".contains(c))
}

#[test]
fn readme_is_at_most_450_lines() {
    let lines = read("README.md").lines().count();
    assert!(
        lines <= MAX_README_LINES,
        "README.md has {lines} lines, more than {MAX_README_LINES}: move reference material to \
         docs/reference/ (issue 41)"
    );
}

/// Every path of the code map exists: the first column's from the repository's root, the
/// second column's from the first column's folder (when it names one). The rest of *How it
/// works* names files of the library's `src/`.
#[test]
fn code_map_paths_exist() {
    let readme = read("README.md");
    let how = section(&readme, "How it works");
    let map = section(&readme, "Code map");
    let library = root().join("crates/splash-sph/src");
    let mut missing = Vec::new();
    let mut rows = 0;
    for line in map.lines().filter(|l| l.starts_with('|')) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let (where_, what) = (cells[1], cells.get(2).copied().unwrap_or(""));
        let bases: Vec<&str> = code_spans(where_)
            .into_iter()
            .filter(|s| is_path(s))
            .collect();
        if bases.is_empty() {
            continue; // the header and its rule
        }
        rows += 1;
        for base in &bases {
            if !root().join(base).exists() {
                missing.push(base.to_string());
            }
        }
        if let [base] = bases[..] {
            for span in code_spans(what).into_iter().filter(|s| is_path(s)) {
                if !root().join(base).join(span).exists() {
                    missing.push(format!("{base}{span}"));
                }
            }
        }
    }
    assert!(rows >= 10, "the code map has {rows} rows with paths");
    let before_map = &how[..how.find("### Code map").unwrap_or(how.len())];
    for span in code_spans(before_map).into_iter().filter(|s| is_path(s)) {
        if !library.join(span).exists() && !root().join(span).exists() {
            missing.push(span.to_string());
        }
    }
    assert!(
        missing.is_empty(),
        "README.md, How it works: no such file or folder: {missing:?}"
    );
}

/// Text with comment markers (`//!`, `///`, `#`) and line breaks taken out, lower case, in
/// sentences (ended by `.`, `;` or `:` before a space).
fn sentences(text: &str) -> Vec<String> {
    let flat: String = text
        .lines()
        .map(|l| l.trim().trim_start_matches('/').trim_start_matches('!'))
        .collect::<Vec<_>>()
        .join(" ")
        .to_lowercase()
        .replace("narrow-band", "narrow band");
    flat.split(". ")
        .flat_map(|s| s.split("; "))
        .flat_map(|s| s.split(": "))
        .map(|s| s.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect()
}

/// A sentence that says all engines give one mesh, without the narrow band's exception.
fn unqualified_engine_equality(sentence: &str) -> bool {
    let same = [
        "same mesh",
        "same surface",
        "same components",
        "identical mesh",
    ]
    .iter()
    .any(|p| sentence.contains(p));
    let all = [
        "all ",
        "every engine",
        "four engines",
        "each engine",
        "the engines",
    ]
    .iter()
    .any(|p| sentence.contains(p));
    let excepted = sentence.contains("narrow band")
        && ["miss", "except", "but for", "beyond"]
            .iter()
            .any(|p| sentence.contains(p));
    sentence.contains("engine") && same && all && !excepted
}

/// The narrow band misses small blobs beyond its band that the full grid finds (fixture
/// frame_0040 at cell r/2: 54 of the full grid's 55 components; docs/papers.md and
/// docs/benchmarks.md): no text may say that every engine gives the same mesh, and the README
/// and the crate docs say what the narrow band misses.
#[test]
fn no_text_says_every_engine_gives_the_same_mesh() {
    let files = [
        "README.md",
        "crates/splash-sph/README.md",
        "crates/splash-sph/src/lib.rs",
        "crates/splash-sph/src/recon/engines/mod.rs",
        "crates/splash-sph/src/config/mod.rs",
        "src/main.rs",
        "crates/splash-py/src/recon.rs",
        "crates/splash-py/python/splash_sph/_native.pyi",
        "crates/splash-py/README.md",
        "docs/index.md",
        "docs/reference/recon.md",
    ];
    let mut wrong = Vec::new();
    for file in files {
        for s in sentences(&read(file)) {
            if unqualified_engine_equality(&s) {
                wrong.push(format!("{file}: \"{s}\""));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "these say every engine gives the same mesh, but the narrow band can miss blobs \
         beyond its band:\n{}",
        wrong.join("\n")
    );
    for file in [
        "README.md",
        "crates/splash-sph/src/lib.rs",
        "crates/splash-sph/src/recon/engines/mod.rs",
        "docs/reference/recon.md",
    ] {
        assert!(
            sentences(&read(file))
                .iter()
                .any(|s| s.contains("narrow band") && s.contains("miss")),
            "{file} does not say what the narrow band misses"
        );
    }
}

/// GitHub's anchor of a heading (mkdocs.yml's slugify does the same): lower case, punctuation
/// but `-` and `_` dropped, spaces turned into `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|&c| c.is_alphanumeric() || c == '-' || c == '_' || c == ' ')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown file's headings, duplicates numbered as GitHub numbers them.
fn anchors(markdown: &str) -> Vec<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = Vec::new();
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        }
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if fenced || hashes == 0 || !line[hashes..].starts_with(' ') {
            continue;
        }
        let base = slug(&line[hashes..].replace('`', ""));
        let n = seen.entry(base.clone()).or_insert(0);
        out.push(if *n == 0 {
            base.clone()
        } else {
            format!("{base}-{n}")
        });
        *n += 1;
    }
    out
}

/// The targets of a Markdown file's inline links and images, outside code.
fn link_targets(markdown: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Code spans hold no links.
        let text: String = line
            .split('`')
            .enumerate()
            .filter(|(i, _)| i % 2 == 0)
            .map(|(_, s)| s)
            .collect::<Vec<_>>()
            .join(" ");
        let mut rest = text.as_str();
        while let Some(i) = rest.find("](") {
            rest = &rest[i + 2..];
            let end = rest.find(')').unwrap_or(rest.len());
            let target = rest[..end].split_whitespace().next().unwrap_or("");
            out.push(target.to_string());
            rest = &rest[end..];
        }
    }
    out
}

fn markdown_files() -> Vec<PathBuf> {
    let mut files = vec![root().join("README.md")];
    let mut dirs = vec![root().join("docs")];
    while let Some(dir) = dirs.pop() {
        for entry in fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// Every relative link of README.md and docs/**/*.md names a file that exists, and its anchor
/// a heading of that file. docs/reference/cli.md and config.md are generated by scripts/docs
/// into its copy of docs/, so links to them are taken on trust.
#[test]
fn readme_and_docs_links_resolve() {
    let generated = [
        root().join("docs/reference/cli.md"),
        root().join("docs/reference/config.md"),
    ];
    let mut broken = Vec::new();
    for file in markdown_files() {
        let text = fs::read_to_string(&file).unwrap();
        let dir = file.parent().unwrap();
        let name = file.strip_prefix(root()).unwrap().display().to_string();
        for target in link_targets(&text) {
            if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let linked = if path.is_empty() {
                file.clone()
            } else {
                normalise(&dir.join(path))
            };
            if generated.contains(&linked) {
                continue;
            }
            if !linked.exists() {
                broken.push(format!("{name}: {target}: no such file"));
                continue;
            }
            if let Some(anchor) = anchor {
                let ok = linked.extension().is_some_and(|e| e == "md")
                    && anchors(&fs::read_to_string(&linked).unwrap())
                        .iter()
                        .any(|a| a == anchor);
                if !ok {
                    broken.push(format!("{name}: {target}: no such heading"));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

/// `a/b/../c` as `a/c`, without touching the file system.
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}
