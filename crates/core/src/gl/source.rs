//! Shader source composed from named parts, with `#line` numbering that
//! lets a driver's message be traced back to the part's file and line.
//!
//! The header (`#version`, extensions, defines, or a verbatim preamble) is
//! numbered as it stands; part `k` (counting from 1) is source string `k`
//! and its line `n` is numbered `k × 10000 + n`, by a `#line` before it
//! (GLSL before 3.30 numbers the line after `#line N` as N + 1, later
//! versions as N). The line alone identifies the part, because Mesa prints
//! source string 0 whatever `#line` says; [`ShaderSource::locate`] turns a
//! driver's `string:line` back into the part's file and line.

/// One part: a file's name (for messages) and its text, with optional lines
/// around it that belong to no file (they take the part's numbering).
#[derive(Clone, Debug, PartialEq, Eq)]
struct Part {
    name: String,
    text: String,
    before: String,
    after: String,
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Header {
    /// `#version {version} core`, then extensions, then defines.
    Built {
        version: u32,
        extensions: Vec<String>,
        defines: Vec<(String, String)>,
    },
    /// Text given whole (it must start with its own `#version`).
    Verbatim { text: String, version: u32 },
}

/// The source of one shader stage: a header and named parts.
///
/// ```
/// use deferred_msaa::gl::ShaderSource;
/// let source = ShaderSource::new()
///     .define("SAMPLES", "4")
///     .part("common.glsl", "float f() { return 1.0; }\n")
///     .part("pass.frag", "out vec4 o;\nvoid main() { o = vec4(f()); }\n");
/// assert!(source.text().contains("#line 20000 2\nout vec4 o;"));
/// assert_eq!(source.locate(0, 20002), Some(("pass.frag", 2)));
/// assert_eq!(source.name(), "common.glsl + pass.frag");
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderSource {
    header: Header,
    parts: Vec<Part>,
}

impl Default for ShaderSource {
    fn default() -> Self {
        Self::new()
    }
}

/// What [`ShaderSource::locate`] names a header line by.
pub const HEADER_NAME: &str = "<header>";

impl ShaderSource {
    /// `#version 150 core` (the crate's floor), no extensions, defines or parts.
    pub fn new() -> Self {
        Self::with_version(150)
    }

    /// `#version {version} core`, no extensions, defines or parts.
    pub fn with_version(version: u32) -> Self {
        ShaderSource {
            header: Header::Built {
                version,
                extensions: Vec::new(),
                defines: Vec::new(),
            },
            parts: Vec::new(),
        }
    }

    /// A header given whole, e.g. a [`preamble`](super::preamble); its
    /// `#version` decides the `#line` rule. A `#line` ending it is dropped:
    /// the parts bring their own, and Mesa keeps the first of two in a row.
    pub fn with_header(text: &str) -> Self {
        let trimmed = match text.trim_end().rsplit_once('\n') {
            Some((head, last)) if last.trim_start().starts_with("#line") => format!("{head}\n"),
            _ => text.to_string(),
        };
        ShaderSource {
            header: Header::Verbatim {
                text: trimmed,
                version: parse_version(text).unwrap_or(150),
            },
            parts: Vec::new(),
        }
    }

    /// The same header without the parts (a sibling stage's start).
    pub fn header_only(&self) -> Self {
        ShaderSource {
            header: self.header.clone(),
            parts: Vec::new(),
        }
    }

    /// Add `#extension {name} : enable` (ignored on a verbatim header).
    pub fn extension(mut self, name: &str) -> Self {
        if let Header::Built { extensions, .. } = &mut self.header {
            extensions.push(name.to_string());
        }
        self
    }

    /// Add several extensions, in order.
    pub fn extensions(self, names: &[&str]) -> Self {
        names.iter().fold(self, |s, n| s.extension(n))
    }

    /// Add `#define {name} {value}` (ignored on a verbatim header).
    pub fn define(mut self, name: &str, value: &str) -> Self {
        if let Header::Built { defines, .. } = &mut self.header {
            defines.push((name.to_string(), value.to_string()));
        }
        self
    }

    /// Add several defines, in order.
    pub fn defines(self, defines: &[(String, String)]) -> Self {
        defines.iter().fold(self, |s, (n, v)| s.define(n, v))
    }

    /// Append the file `name` with its `text`.
    pub fn part(self, name: &str, text: &str) -> Self {
        self.part_between("", name, text, "")
    }

    /// Append `name` with its `main()` renamed to `new_main` (a `#define`
    /// before it, an `#undef` after), so that a later part can call it.
    pub fn part_renaming_main(self, name: &str, text: &str, new_main: &str) -> Self {
        self.part_between(
            &format!("#define main {new_main}\n"),
            name,
            text,
            "#undef main\n",
        )
    }

    fn part_between(mut self, before: &str, name: &str, text: &str, after: &str) -> Self {
        self.parts.push(Part {
            name: name.to_string(),
            text: text.to_string(),
            before: before.to_string(),
            after: after.to_string(),
        });
        self
    }

    /// The parts' names joined by ` + ` (what errors call the shader).
    pub fn name(&self) -> String {
        let names: Vec<&str> = self.parts.iter().map(|p| p.name.as_str()).collect();
        names.join(" + ")
    }

    fn version(&self) -> u32 {
        match &self.header {
            Header::Built { version, .. } | Header::Verbatim { version, .. } => *version,
        }
    }

    /// The header's text alone.
    pub fn header_text(&self) -> String {
        match &self.header {
            Header::Verbatim { text, .. } => text.clone(),
            Header::Built {
                version,
                extensions,
                defines,
            } => {
                let mut text = format!("#version {version} core\n");
                for ext in extensions {
                    text.push_str(&format!("#extension {ext} : enable\n"));
                }
                for (name, value) in defines {
                    text.push_str(&format!("#define {name} {value}\n"));
                }
                text
            }
        }
    }

    /// The `#line` that makes the next line part `string`'s line 1.
    fn line_directive(&self, string: usize) -> String {
        let first = string * LINES_PER_PART + usize::from(self.version() >= 330);
        format!("#line {first} {string}\n")
    }

    /// The whole text handed to the driver.
    pub fn text(&self) -> String {
        let mut text = self.header_text();
        for (k, part) in self.parts.iter().enumerate() {
            if !text.ends_with('\n') {
                text.push('\n');
            }
            text.push_str(&part.before);
            text.push_str(&self.line_directive(k + 1));
            text.push_str(&part.text);
            if !text.ends_with('\n') {
                text.push('\n');
            }
            text.push_str(&part.after);
        }
        text
    }

    /// The file and line a driver's `string:line` location refers to:
    /// string 0 is the header ([`HEADER_NAME`]), string `k` part `k - 1`.
    pub fn locate(&self, string: usize, line: usize) -> Option<(&str, usize)> {
        let (string, line) = split_line(string, line);
        match string {
            0 => Some((HEADER_NAME, line)),
            k => self.parts.get(k - 1).map(|p| (p.name.as_str(), line)),
        }
    }

    /// The text of line `line` (from 1) of the file [`locate`](Self::locate) named.
    fn line_text(&self, string: usize, line: usize) -> Option<String> {
        let text = match string {
            0 => self.header_text(),
            k => self.parts.get(k - 1)?.text.clone(),
        };
        text.lines().nth(line.checked_sub(1)?).map(str::to_string)
    }

    /// For each location a driver log names: `file:line: message`, then the
    /// file's lines around it, the offending one marked `>`.
    pub fn explain(&self, log: &str) -> String {
        let mut out = String::new();
        let mut seen = Vec::new();
        for entry in log_entries(log) {
            let (part, line) = split_line(entry.string, entry.line);
            let Some((file, _)) = self.locate(part, line) else {
                continue;
            };
            out.push_str(&format!("{file}:{line}: {}\n", entry.message));
            if seen.contains(&(part, line)) {
                continue;
            }
            seen.push((part, line));
            for k in line.saturating_sub(1).max(1)..=line + 1 {
                if let Some(text) = self.line_text(part, k) {
                    let marker = if k == line { ">" } else { " " };
                    out.push_str(&format!("{marker} {file}:{k:>4} | {text}\n"));
                }
            }
        }
        out
    }
}

/// How far apart the parts' line numbers are.
const LINES_PER_PART: usize = 10_000;

/// A driver's `string:line` as (part, line within it).
fn split_line(string: usize, line: usize) -> (usize, usize) {
    if line > LINES_PER_PART {
        (line / LINES_PER_PART, line % LINES_PER_PART)
    } else {
        (string, line)
    }
}

fn parse_version(text: &str) -> Option<u32> {
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("#version"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// A located line of a driver log.
#[derive(Debug, PartialEq, Eq)]
pub(crate) struct LogEntry {
    pub(crate) string: usize,
    pub(crate) line: usize,
    pub(crate) message: String,
}

/// The located entries of a driver log: Mesa writes `0:12(5): error: …`,
/// NVIDIA `0(12) : error …`, AMD `ERROR: 0:12: …`.
pub(crate) fn log_entries(log: &str) -> Vec<LogEntry> {
    let mut entries = Vec::new();
    for entry in log.lines() {
        let (severity, rest) = if let Some(r) = entry.strip_prefix("ERROR: ") {
            ("error: ", r)
        } else if let Some(r) = entry.strip_prefix("WARNING: ") {
            ("warning: ", r)
        } else {
            ("", entry)
        };
        let (string, rest) = split_number(rest);
        let Some(string) = string else { continue };
        let Some(rest) = rest.strip_prefix(':').or_else(|| rest.strip_prefix('(')) else {
            continue;
        };
        let (line, rest) = split_number(rest);
        let Some(line) = line else { continue };
        // What is left is `(col): msg`, `) : msg` or `: msg`.
        let rest = rest
            .strip_prefix('(')
            .map_or(rest, |r| r.trim_start_matches(|c: char| c.is_ascii_digit()));
        let message = rest.trim_start_matches([')', ':', ' ']).trim_end();
        entries.push(LogEntry {
            string,
            line,
            message: format!("{severity}{message}"),
        });
    }
    entries
}

fn split_number(s: &str) -> (Option<usize>, &str) {
    let end = s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
    (s[..end].parse().ok(), &s[end..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_driver_locations() {
        let mesa = log_entries("1:12(5): error: `x' undeclared");
        assert_eq!(
            mesa,
            vec![LogEntry {
                string: 1,
                line: 12,
                message: "error: `x' undeclared".into()
            }]
        );
        let nv = log_entries("2(7) : error C1008: undefined variable");
        assert_eq!((nv[0].string, nv[0].line), (2, 7));
        assert_eq!(nv[0].message, "error C1008: undefined variable");
        let amd = log_entries("ERROR: 0:3: 'y' : undeclared");
        assert_eq!((amd[0].string, amd[0].line), (0, 3));
        assert_eq!(amd[0].message, "error: 'y' : undeclared");
        assert!(log_entries("link failed").is_empty());
    }

    #[test]
    fn numbers_each_part_from_one() {
        let s = ShaderSource::new()
            .extension("GL_ARB_x")
            .define("A", "1")
            .part_renaming_main("model.frag", "void main() {}\n", "model_main")
            .part("wrap.frag", "void main() { model_main(); }");
        assert_eq!(
            s.text(),
            "#version 150 core\n#extension GL_ARB_x : enable\n#define A 1\n\
             #define main model_main\n#line 10000 1\nvoid main() {}\n#undef main\n\
             #line 20000 2\nvoid main() { model_main(); }\n"
        );
        assert!(
            ShaderSource::with_version(330)
                .part("a", "x")
                .text()
                .contains("#line 10001 1\n")
        );
        assert_eq!(s.locate(1, 1), Some(("model.frag", 1)));
        assert_eq!(s.locate(0, 20003), Some(("wrap.frag", 3)));
        assert_eq!(s.locate(0, 2), Some((HEADER_NAME, 2)));
        assert_eq!(s.locate(3, 1), None);
    }

    #[test]
    fn explains_a_log_by_file_and_line() {
        let s = ShaderSource::new()
            .part("a.frag", "float f() {\n  return 1.0;\n}\n")
            .part("b.frag", "void main() {\n  x = 1;\n}\n");
        let text = s.explain("0:2(3): error: `x' undeclared\n0:20002(3): error: `x' undeclared");
        assert!(text.contains("b.frag:2: error: `x' undeclared\n"), "{text}");
        assert!(text.contains("> b.frag:   2 |   x = 1;"), "{text}");
        assert!(text.contains("  b.frag:   1 | void main() {"), "{text}");
        assert!(text.contains("<header>:2: error"), "{text}");
    }
}
