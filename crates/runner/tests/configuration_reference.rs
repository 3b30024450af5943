//! docs/configuration.md is generated from the code; this test regenerates it and fails when the file
//! differs (run with STRIDE_UPDATE_DOCS=1 to rewrite it). Every key of the default configuration must
//! have a meaning: runner keys from `stride_runner::config::reference::RUNNER_KEYS`, layer keys from the
//! documentation comments of the layer crates' config fields.
mod common;

use std::collections::BTreeMap;
use std::path::Path;

use stride_runner::config::reference::render;
use stride_runner::config::ScenarioConfig;

/// `field name → [(struct name, doc)]` from the `///` comments above `pub field:` lines of a crate.
fn field_docs(dir: &Path) -> BTreeMap<String, Vec<(String, String)>> {
    let mut out: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    for f in files
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
    {
        let text = std::fs::read_to_string(&f).unwrap();
        let mut doc: Vec<String> = Vec::new();
        let mut current = String::new();
        for line in text.lines() {
            let t = line.trim();
            if let Some(rest) = t
                .strip_prefix("pub struct ")
                .or_else(|| t.strip_prefix("pub enum "))
            {
                current = rest
                    .split(|c: char| !c.is_alphanumeric() && c != '_')
                    .next()
                    .unwrap_or("")
                    .to_string();
            }
            if let Some(d) = t.strip_prefix("///") {
                doc.push(d.trim().to_string());
                continue;
            }
            if t.starts_with("#[") {
                continue;
            }
            let field = t
                .strip_prefix("pub ")
                .and_then(|r| r.split_once(':'))
                .map(|(n, _)| n.trim())
                .filter(|n| {
                    n.chars()
                        .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
                });
            // Enum struct-variant fields are not `pub`: `name: Type,` right after docs.
            let field = field.or_else(|| {
                (!doc.is_empty())
                    .then(|| t.split_once(':').map(|(n, _)| n.trim()))
                    .flatten()
                    .filter(|n| {
                        !n.is_empty()
                            && n.chars()
                                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
                    })
            });
            if let Some(name) = field {
                if !doc.is_empty() {
                    out.entry(name.to_string())
                        .or_default()
                        .push((current.clone(), doc.join(" ")));
                }
            }
            doc.clear();
        }
    }
    out
}

fn camel(s: &str) -> String {
    s.split('_')
        .map(|w| {
            let mut c = w.chars();
            c.next()
                .map(|f| f.to_uppercase().collect::<String>() + c.as_str())
                .unwrap_or_default()
        })
        .collect()
}

#[test]
fn configuration_reference_matches_the_code() {
    let root = common::root();
    // Sections and the crates whose config types they embed (QP settings live in stride-qp).
    let crates: [(&str, &[&str]); 5] = [
        ("planner", &["planner"]),
        ("simplified", &["simplified", "qp"]),
        ("wbc", &["wbc", "qp"]),
        ("sim", &["sim"]),
        ("estimation", &["estimation"]),
    ];
    let docs: BTreeMap<&str, _> = crates
        .iter()
        .map(|(sec, dirs)| {
            let mut all: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
            for dir in dirs.iter() {
                for (k, v) in field_docs(&root.join("crates").join(dir).join("src")) {
                    all.entry(k).or_default().extend(v);
                }
            }
            (*sec, all)
        })
        .collect();
    let lookup = |key: &str| -> Option<String> {
        let section = key.split(['.', '[']).next()?;
        let d = docs.get(section)?;
        let parts: Vec<&str> = key.split('.').collect();
        let field = parts.last()?.trim_end_matches("[]");
        if field == "type" {
            return Some(
                "Variant tag of the entry (see the layer's config enum for the allowed values)."
                    .into(),
            );
        }
        let candidates = d.get(field)?;
        let parent = parts
            .get(parts.len().wrapping_sub(2))
            .map(|p| camel(p.trim_end_matches("[]")))
            .unwrap_or_default();
        let best = candidates
            .iter()
            .find(|(s, _)| {
                !parent.is_empty() && (s.starts_with(&parent) || parent.starts_with(s.as_str()))
            })
            // e.g. `simplified.predictive.horizon` is a field of `DcmPredictiveConfig`
            .or_else(|| {
                candidates
                    .iter()
                    .find(|(s, _)| !parent.is_empty() && s.contains(&parent))
            })
            .or_else(|| candidates.first())?;
        Some(best.1.clone())
    };
    let default = toml::Table::try_from(ScenarioConfig::default()).unwrap();
    let (text, missing) = render(&default, &lookup);
    assert!(
        missing.is_empty(),
        "keys without a meaning (add to RUNNER_KEYS or document the layer field): {missing:#?}"
    );
    let path = root.join("docs/configuration.md");
    if std::env::var_os("STRIDE_UPDATE_DOCS").is_some() {
        std::fs::write(&path, &text).unwrap();
    }
    let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        on_disk == text,
        "docs/configuration.md is out of date: run `STRIDE_UPDATE_DOCS=1 cargo test -p stride-runner --test configuration_reference`"
    );
}
