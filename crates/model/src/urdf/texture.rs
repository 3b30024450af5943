//! Removal of the `<texture/>` elements urdf-rs rejects.

/// Removes `<texture .../>` elements that have no `filename` attribute (allowed by the URDF XSD, rejected by
/// urdf-rs 0.10). Textures are visual-only and irrelevant to dynamics.
pub(crate) fn strip_textures_without_filename(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<texture") {
        let after = &rest[start + "<texture".len()..];
        let is_tag = after
            .chars()
            .next()
            .is_some_and(|c| c.is_whitespace() || c == '/' || c == '>');
        let end = after.find('>');
        match (is_tag, end) {
            (true, Some(end)) => {
                let tag = &after[..end];
                let self_closing = tag.trim_end().ends_with('/');
                if self_closing && !tag.contains("filename") {
                    out.push_str(&rest[..start]);
                } else {
                    out.push_str(&rest[..start + "<texture".len() + end + 1]);
                }
                rest = &after[end + 1..];
            }
            _ => {
                out.push_str(&rest[..start + "<texture".len()]);
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}
