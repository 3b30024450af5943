//! Reading scenario files: the `include` list, deep-merge overlay and error locations.
//!
//! A scenario file may start with `include = ["robots/x.toml", "layers/y.toml"]` (paths relative to the
//! including file). Included files are merged first, in list order, then the including file on top:
//! tables are merged key by key recursively, any other value (numbers, strings, arrays) is replaced
//! whole by the later file. Includes may include further files; cycles are rejected.
//!
//! Every file is parsed with its byte spans kept, and the spans are shifted into one *virtual buffer*
//! (file 0 occupies bytes `0..len0`, file 1 the next range, and so on). The merged, still-spanned
//! document is deserialized with serde directly, so any error the deserializer reports carries a span
//! that maps back to exactly one file, line and column: the file where the offending key was written.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::Serialize;
use toml::de::{DeArray, DeTable, DeValue};
use toml::Spanned;

use super::ConfigError;

/// One file that contributed to a scenario, with its place in the virtual buffer.
#[derive(Debug, Clone)]
pub struct SourceFile {
    /// Path as opened (the include path joined to the including file's folder).
    pub path: PathBuf,
    /// Full text of the file.
    pub text: String,
    /// Offset of this file's first byte in the virtual buffer.
    pub offset: usize,
}

/// Where a key or value was written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// File that holds it.
    pub path: PathBuf,
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in characters).
    pub column: usize,
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}:{}", self.path.display(), self.line, self.column)
    }
}

/// All files of one scenario, in merge order (includes before includers).
#[derive(Debug, Clone, Default)]
pub struct SourceMap {
    /// The files, in merge order.
    pub files: Vec<SourceFile>,
    /// Span of each leaf/table key of the merged document, by dotted key path, pointing at the *value*
    /// that won the merge (used to locate errors found after deserialization, and to resolve paths).
    pub value_spans: Vec<(String, Range<usize>)>,
    /// Span of the key itself, by dotted key path.
    pub key_spans: Vec<(String, Range<usize>)>,
}

impl SourceMap {
    /// Maps a virtual-buffer offset to a file location.
    pub fn locate(&self, offset: usize) -> Option<Location> {
        let file = self
            .files
            .iter()
            .rev()
            .find(|f| offset >= f.offset && offset <= f.offset + f.text.len())?;
        if file.path == Path::new(DEFAULTS_PATH) {
            // Built-in defaults were not written by the user: no location.
            return None;
        }
        let local = offset - file.offset;
        let before = &file.text[..local.min(file.text.len())];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        Some(Location {
            path: file.path.clone(),
            line,
            column,
        })
    }

    /// Location of the key `path` (dotted), if it was written in some file.
    pub fn key_location(&self, path: &str) -> Option<Location> {
        self.key_spans
            .iter()
            .find(|(p, _)| p == path)
            .and_then(|(_, s)| self.locate(s.start))
    }

    /// Location of the value of key `path` (dotted), falling back to the closest written parent table.
    pub fn value_location(&self, path: &str) -> Option<Location> {
        let mut p = path.to_string();
        loop {
            if let Some((_, s)) = self.value_spans.iter().find(|(q, _)| *q == p) {
                return self.locate(s.start);
            }
            match p.rfind('.') {
                Some(i) => p.truncate(i),
                None => return None,
            }
        }
    }

    /// Folder of the file in which the value at `path` was written (for resolving relative paths).
    pub fn value_dir(&self, path: &str) -> Option<PathBuf> {
        let loc = self.value_location(path)?;
        Some(
            loc.path
                .parent()
                .map_or_else(PathBuf::new, Path::to_path_buf),
        )
    }

    /// The dotted key path whose key or value span contains `span` most tightly.
    fn path_at(&self, span: &Range<usize>) -> Option<String> {
        let mut best: Option<(&String, usize)> = None;
        for (p, s) in self.key_spans.iter().chain(self.value_spans.iter()) {
            if s.start <= span.start && span.end <= s.end.max(s.start + 1) {
                let len = s.end - s.start;
                if best.is_none_or(|(_, l)| len < l) {
                    best = Some((p, len));
                }
            }
        }
        best.map(|(p, _)| p.clone())
    }
}

const MAX_INCLUDE_DEPTH: usize = 16;

/// Name of the virtual first file holding the built-in defaults.
pub const DEFAULTS_PATH: &str = "<built-in defaults>";

/// Reads `path` and every file it includes, depth-first, includes before includers.
fn collect(
    path: &Path,
    stack: &mut Vec<PathBuf>,
    out: &mut Vec<SourceFile>,
) -> Result<(), ConfigError> {
    let canonical = path.canonicalize().map_err(|e| ConfigError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    if stack.contains(&canonical) {
        return Err(ConfigError::IncludeCycle {
            path: path.to_path_buf(),
        });
    }
    if stack.len() >= MAX_INCLUDE_DEPTH {
        return Err(ConfigError::IncludeCycle {
            path: path.to_path_buf(),
        });
    }
    let text = std::fs::read_to_string(path).map_err(|e| ConfigError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    // A first, span-less look at the include list (syntax errors are reported with the file).
    let doc = DeTable::parse(&text).map_err(|e| {
        let (line, column) = line_col(&text, e.span().map_or(0, |s| s.start));
        ConfigError::Syntax {
            location: Location {
                path: path.to_path_buf(),
                line,
                column,
            },
            message: e.message().to_string(),
        }
    })?;
    let mut includes = Vec::new();
    if let Some(inc) = doc.get_ref().get("include") {
        let (line, column) = line_col(&text, inc.span().start);
        let loc = Location {
            path: path.to_path_buf(),
            line,
            column,
        };
        let bad = || ConfigError::Invalid {
            location: Some(loc.clone()),
            key: "include".into(),
            message: "expected an array of file paths (strings), relative to this file".into(),
        };
        let arr = inc.get_ref().as_array().ok_or_else(bad)?;
        for item in arr.iter() {
            let s = item.get_ref().as_str().ok_or_else(bad)?;
            includes.push(s.to_string());
        }
    }
    drop(doc);
    stack.push(canonical);
    let dir = path.parent().map_or_else(PathBuf::new, Path::to_path_buf);
    for inc in includes {
        collect(&dir.join(inc), stack, out)?;
    }
    stack.pop();
    let offset = out.last().map_or(0, |f| f.offset + f.text.len() + 1);
    out.push(SourceFile {
        path: path.to_path_buf(),
        text,
        offset,
    });
    Ok(())
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

fn shift_value<'i>(v: Spanned<DeValue<'i>>, off: usize) -> Spanned<DeValue<'i>> {
    let span = v.span();
    let inner = match v.into_inner() {
        DeValue::Table(t) => DeValue::Table(shift_table(t, off)),
        DeValue::Array(a) => {
            let mut out = DeArray::new();
            for item in a {
                out.push(shift_value(item, off));
            }
            DeValue::Array(out)
        }
        other => other,
    };
    Spanned::new(span.start + off..span.end + off, inner)
}

fn shift_table<'i>(t: DeTable<'i>, off: usize) -> DeTable<'i> {
    let mut out = DeTable::new();
    for (k, v) in t {
        let ks = k.span();
        out.insert(
            Spanned::new(ks.start + off..ks.end + off, k.into_inner()),
            shift_value(v, off),
        );
    }
    out
}

/// Deep merge: tables merge recursively, everything else is replaced by `over`.
fn merge<'i>(base: &mut DeTable<'i>, over: DeTable<'i>) {
    for (k, v) in over {
        let existing = base.remove_entry(k.get_ref().as_ref() as &str);
        match existing {
            Some((bk, bv)) => {
                let bspan = bv.span();
                match (bv.into_inner(), v) {
                    (DeValue::Table(mut bt), v) if v.get_ref().is_table() => {
                        let vspan = v.span();
                        if let DeValue::Table(vt) = v.into_inner() {
                            merge(&mut bt, vt);
                        }
                        let _ = bspan;
                        // The key of the later file wins so errors point at the latest writer.
                        base.insert(k, Spanned::new(vspan, DeValue::Table(bt)));
                        let _ = bk;
                    }
                    (_, v) => {
                        base.insert(k, v);
                    }
                }
            }
            None => {
                base.insert(k, v);
            }
        }
    }
}

fn record_spans(
    t: &DeTable<'_>,
    prefix: &str,
    keys: &mut Vec<(String, Range<usize>)>,
    values: &mut Vec<(String, Range<usize>)>,
) {
    for (k, v) in t.iter() {
        let path = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        keys.push((path.clone(), k.span()));
        values.push((path.clone(), v.span()));
        match v.get_ref() {
            DeValue::Table(inner) => record_spans(inner, &path, keys, values),
            DeValue::Array(a) => {
                for (i, item) in a.iter().enumerate() {
                    let ip = format!("{path}[{i}]");
                    values.push((ip.clone(), item.span()));
                    if let DeValue::Table(inner) = item.get_ref() {
                        record_spans(inner, &ip, keys, values);
                    }
                }
            }
            _ => {}
        }
    }
}

/// A scenario as read from disk: the merged document deserialized into `T`, plus where each key came from.
#[derive(Debug, Clone)]
pub struct Loaded<T> {
    /// The deserialized configuration.
    pub value: T,
    /// The files and key locations.
    pub sources: SourceMap,
    /// The merged document as a plain TOML table (what the log stores as "the full config").
    pub merged: toml::Table,
}

/// Reads `path` with its includes and deserializes the merged document into `T`.
///
/// The serialized `T::default()` is merged first, as a virtual file: every section is complete before
/// the user's files are overlaid, so a file can change one key of a layer's configuration (say
/// `wbc.ik.feedback`) without restating the fields that have no serde default (the task list).
/// Keys in `exclusive` (dotted; tables that select one alternative, such as an externally tagged enum, or
/// tables whose default names parts of one robot) are not pre-filled from the defaults: a file that
/// writes another alternative must not be merged with the default one (serde fills them from the type's
/// default when no file writes them).
pub fn load<T: DeserializeOwned + Serialize + Default>(
    path: &Path,
    exclusive: &[&str],
) -> Result<Loaded<T>, ConfigError> {
    let mut files = Vec::new();
    collect(path, &mut Vec::new(), &mut files)?;
    load_files(files, exclusive)
}

/// Deserializes in-memory files (merge order: the built-in defaults, then earlier files overlaid by later
/// ones). Include lists
/// in these texts are ignored; used by tests and by replay from a log.
pub fn load_files<T: DeserializeOwned + Serialize + Default>(
    mut files: Vec<SourceFile>,
    exclusive: &[&str],
) -> Result<Loaded<T>, ConfigError> {
    let bad = |e: String| ConfigError::Invalid {
        location: None,
        key: String::new(),
        message: format!("the built-in defaults do not serialize: {e}"),
    };
    let mut table = toml::Table::try_from(T::default()).map_err(|e| bad(e.to_string()))?;
    for k in exclusive {
        remove_dotted(&mut table, k);
    }
    let defaults = toml::to_string(&table).map_err(|e| bad(e.to_string()))?;
    files.insert(
        0,
        SourceFile {
            path: PathBuf::from(DEFAULTS_PATH),
            text: defaults,
            offset: 0,
        },
    );
    let mut sources = SourceMap {
        files,
        ..SourceMap::default()
    };
    // Re-assign offsets (callers of load_files may pass zeros).
    let mut off = 0;
    for f in sources.files.iter_mut() {
        f.offset = off;
        off += f.text.len() + 1;
    }
    let mut merged: DeTable<'_> = DeTable::new();
    let mut root_span = 0..0;
    for f in sources.files.iter() {
        let doc = DeTable::parse(&f.text).map_err(|e| {
            let (line, column) = line_col(&f.text, e.span().map_or(0, |s| s.start));
            ConfigError::Syntax {
                location: Location {
                    path: f.path.clone(),
                    line,
                    column,
                },
                message: e.message().to_string(),
            }
        })?;
        let span = doc.span();
        let mut t = shift_table(doc.into_inner(), f.offset);
        t.remove("include");
        root_span = span.start + f.offset..span.end + f.offset;
        merge(&mut merged, t);
    }
    record_spans(
        &merged,
        "",
        &mut sources.key_spans,
        &mut sources.value_spans,
    );
    let mut plain = toml::Table::new();
    for f in sources.files.iter() {
        if let Ok(mut t) = f.text.parse::<toml::Table>() {
            t.remove("include");
            merge_plain(&mut plain, t);
        }
    }
    let de = toml::de::Deserializer::from(Spanned::new(root_span, merged));
    let value = T::deserialize(de).map_err(|e| {
        let span = e.span();
        let location = span.as_ref().and_then(|s| sources.locate(s.start));
        let mut key = span
            .as_ref()
            .and_then(|s| sources.path_at(s))
            .unwrap_or_default();
        let mut message = e.message().to_string();
        if let Some(field) = unknown_field_name(&message) {
            if let Some((_, new, meaning)) = RENAMED_KEYS.iter().find(|(old, ..)| *old == field) {
                message = format!("`{field}` was renamed `{new}` ({meaning}); {message}");
            }
            if !key.ends_with(&field) {
                key = if key.is_empty() {
                    field
                } else {
                    format!("{key}.{field}")
                };
            }
        }
        ConfigError::Invalid {
            location,
            key,
            message,
        }
    })?;
    Ok(Loaded {
        value,
        sources,
        merged: plain,
    })
}

/// Keys renamed since earlier versions: `(old, new, what the new name means)`; an old key is still an
/// unknown key, and the error names its replacement.
pub const RENAMED_KEYS: &[(&str, &str, &str)] = &[
    (
        "step_length_max",
        "feet_distance_max",
        "the straight-line distance between the sole origins at touch-down, the width included",
    ),
    (
        "step_length_min",
        "feet_distance_min",
        "the straight-line distance between the sole origins at touch-down, the width included",
    ),
];

/// Removes the dotted key `key` (`a.b.c`) from `table`, if present.
fn remove_dotted(table: &mut toml::Table, key: &str) {
    match key.split_once('.') {
        None => {
            table.remove(key);
        }
        Some((head, rest)) => {
            if let Some(toml::Value::Table(t)) = table.get_mut(head) {
                remove_dotted(t, rest);
            }
        }
    }
}

fn unknown_field_name(msg: &str) -> Option<String> {
    let rest = msg.strip_prefix("unknown field `")?;
    let end = rest.find('`')?;
    Some(rest[..end].to_string())
}

fn merge_plain(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(bt)), toml::Value::Table(vt)) => merge_plain(bt, vt),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}
