//! Plain-WGSL composition: the subset of naga_oil's preprocessor the library's modules use
//! (`#define_import_path`, `#import`, `#ifdef` / `#ifndef` / `#else` / `#endif`, `#{DEF}`),
//! resolved by concatenation in dependency order.

use std::collections::BTreeSet;
use std::fmt;

use super::Module;

/// Why a shader could not be composed into plain WGSL.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ShaderError {
    /// An `#import` names no module of the library (plain composition resolves `mcg::*` only;
    /// compose other imports with naga_oil).
    UnknownImport {
        /// The file: `"your shader"` or a module's file path.
        file: String,
        /// 1-based line of the `#import`.
        line: usize,
        /// The path as written.
        path: String,
    },
    /// A module or your shader reads a shader def that was not given.
    MissingShaderDef {
        /// The file: `"your shader"` or a module's file path.
        file: String,
        /// 1-based line.
        line: usize,
        /// The def's name, e.g. `MCG_HASHGRID_GROUP`.
        def: String,
    },
    /// An `#ifdef` without `#endif`, or an `#else` / `#endif` without `#ifdef`.
    UnbalancedConditional {
        /// The file.
        file: String,
        /// 1-based line where it was noticed.
        line: usize,
    },
}

impl fmt::Display for ShaderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ShaderError::UnknownImport { file, line, path } => write!(
                f,
                "{file}:{line}: `#import {path}` names no mcg module (known: {})",
                Module::ALL.map(Module::import_path).join(", ")
            ),
            ShaderError::MissingShaderDef { file, line, def } => {
                write!(f, "{file}:{line}: shader def `{def}` is not set")
            }
            ShaderError::UnbalancedConditional { file, line } => {
                write!(f, "{file}:{line}: unbalanced #ifdef / #else / #endif")
            }
        }
    }
}

impl std::error::Error for ShaderError {}

/// The file name errors in the caller's own source carry.
const YOUR_SHADER: &str = "your shader";

/// One imported path: a module and, for an item import, the item.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Import {
    /// The module's path as written (`mcg::vmf`), or the whole path when it names no module.
    pub module: String,
    /// The item (`vmf_pdf`), `None` for a whole-module import.
    pub item: Option<String>,
    /// 1-based line of the `#import`.
    pub line: usize,
}

/// The `#import` directives of `source`, each path expanded (`a::{b, c::d}` gives `a::b` and
/// `a::c::d`) and split into module and item.
pub(crate) fn imports(source: &str) -> impl Iterator<Item = Import> + '_ {
    directives(source).into_iter().flat_map(|(line, text)| {
        let mut paths = Vec::new();
        expand(text.trim(), "", &mut paths);
        paths.into_iter().map(move |path| split_path(&path, line))
    })
}

/// The `#import` directives as (1-based first line, text after `#import`), multi-line lists
/// joined.
fn directives(source: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut open: Option<(usize, String)> = None;
    for (i, line) in source.lines().enumerate() {
        if let Some((start, mut text)) = open.take() {
            text.push(' ');
            text.push_str(line.trim());
            if braces_closed(&text) {
                out.push((start, text));
            } else {
                open = Some((start, text));
            }
        } else if let Some(rest) = line.trim_start().strip_prefix("#import") {
            let text = rest.trim().to_string();
            if braces_closed(&text) {
                out.push((i + 1, text));
            } else {
                open = Some((i + 1, text));
            }
        }
    }
    out.extend(open);
    out
}

fn braces_closed(text: &str) -> bool {
    text.matches('{').count() <= text.matches('}').count()
}

/// Expands `prefix::{a, b::{c}}` into full paths; `as` aliases are dropped (plain WGSL strips
/// every qualifier anyway).
fn expand(text: &str, prefix: &str, out: &mut Vec<String>) {
    let text = text.trim().trim_end_matches(';').trim();
    let text = text.split(" as ").next().unwrap_or(text).trim();
    if let Some(open) = text.find('{') {
        let head = text[..open].trim().trim_end_matches("::");
        let inner = &text[open + 1..text.rfind('}').unwrap_or(text.len())];
        let base = join(prefix, head);
        let mut depth = 0;
        let mut start = 0;
        for (i, c) in inner.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand(&inner[start..i], &base, out);
                    start = i + 1;
                }
                _ => {}
            }
        }
        expand(&inner[start..], &base, out);
    } else if !text.is_empty() {
        out.push(join(prefix, text));
    }
}

fn join(prefix: &str, rest: &str) -> String {
    match (prefix.is_empty(), rest.is_empty()) {
        (true, _) => rest.to_string(),
        (_, true) => prefix.to_string(),
        _ => format!("{prefix}::{rest}"),
    }
}

fn split_path(path: &str, line: usize) -> Import {
    if Module::from_import_path(path).is_some() {
        return Import {
            module: path.to_string(),
            item: None,
            line,
        };
    }
    match path.rsplit_once("::") {
        Some((module, item)) if Module::from_import_path(module).is_some() => Import {
            module: module.to_string(),
            item: Some(item.to_string()),
            line,
        },
        _ => Import {
            module: path.to_string(),
            item: None,
            line,
        },
    }
}

/// What a set of imports pulls in: the modules (transitively) and the constants named.
#[derive(Default)]
struct Needs {
    modules: BTreeSet<Module>,
    constants: BTreeSet<String>,
    all_constants: bool,
}

impl Needs {
    fn add_imports(&mut self, source: &str, file: &str) -> Result<(), ShaderError> {
        for import in imports(source) {
            let module = Module::from_import_path(&import.module).ok_or_else(|| {
                ShaderError::UnknownImport {
                    file: file.to_string(),
                    line: import.line,
                    path: match &import.item {
                        Some(item) => format!("{}::{item}", import.module),
                        None => import.module.clone(),
                    },
                }
            })?;
            if module == Module::Constants {
                match import.item {
                    Some(item) => {
                        self.constants.insert(item);
                    }
                    None => self.all_constants = true,
                }
            }
            self.add_module(module)?;
        }
        Ok(())
    }

    fn add_module(&mut self, module: Module) -> Result<(), ShaderError> {
        if self.modules.insert(module) {
            self.add_imports(module.source(), module.file_path())?;
        }
        Ok(())
    }
}

/// The value of a shader def.
fn def_value(defs: &[(&str, u32)], name: &str) -> Option<u32> {
    defs.iter().find(|(n, _)| *n == name).map(|&(_, v)| v)
}

/// Runs the preprocessor over `source`: directive lines and lines in inactive branches become
/// empty (line numbers are kept), `#{DEF}` is substituted, and with `strip_qualifiers` every
/// `name::` qualifier is removed (WGSL itself never uses `::`).
fn preprocess(
    source: &str,
    file: &str,
    defs: &[(&str, u32)],
    strip_qualifiers: bool,
) -> Result<String, ShaderError> {
    let mut out = String::with_capacity(source.len());
    // Each entry: whether this branch is active, and whether the enclosing one is.
    let mut stack: Vec<(bool, bool)> = Vec::new();
    let mut in_import = false;
    let mut line_no = 0;
    for (i, line) in source.lines().enumerate() {
        line_no = i + 1;
        let active = stack.last().is_none_or(|&(this, _)| this);
        let trimmed = line.trim_start();
        if in_import {
            in_import = !line.contains('}');
            out.push('\n');
            continue;
        }
        if let Some(name) = trimmed
            .strip_prefix("#ifdef ")
            .or_else(|| trimmed.strip_prefix("#ifndef "))
        {
            let defined = def_value(defs, name.trim()).is_some();
            let wanted = trimmed.starts_with("#ifdef ");
            stack.push((active && defined == wanted, active));
        } else if trimmed.starts_with("#else") {
            let (this, outer) = stack.pop().ok_or_else(|| unbalanced(file, line_no))?;
            stack.push((outer && !this, outer));
        } else if trimmed.starts_with("#endif") {
            stack.pop().ok_or_else(|| unbalanced(file, line_no))?;
        } else if trimmed.starts_with("#import") {
            in_import = trimmed.contains('{') && !trimmed.contains('}');
        } else if trimmed.starts_with("#define_import_path") || !active {
        } else {
            let substituted = substitute(line, file, line_no, defs)?;
            if strip_qualifiers {
                out.push_str(&strip(&substituted));
            } else {
                out.push_str(&substituted);
            }
        }
        out.push('\n');
    }
    if !stack.is_empty() {
        return Err(unbalanced(file, line_no));
    }
    Ok(out)
}

fn unbalanced(file: &str, line: usize) -> ShaderError {
    ShaderError::UnbalancedConditional {
        file: file.to_string(),
        line,
    }
}

/// `#{NAME}` replaced by the def's value.
fn substitute(
    line: &str,
    file: &str,
    line_no: usize,
    defs: &[(&str, u32)],
) -> Result<String, ShaderError> {
    let mut out = String::with_capacity(line.len());
    let mut rest = line;
    while let Some(start) = rest.find("#{") {
        let end = rest[start..].find('}').map_or(rest.len(), |e| start + e);
        let name = &rest[start + 2..end];
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            // Not a def (e.g. `#{k ≥ 1}` in a comment): keep it as it is.
            out.push_str(&rest[..start + 2]);
            rest = &rest[start + 2..];
            continue;
        }
        let value = def_value(defs, name).ok_or_else(|| ShaderError::MissingShaderDef {
            file: file.to_string(),
            line: line_no,
            def: name.to_string(),
        })?;
        out.push_str(&rest[..start]);
        out.push_str(&value.to_string());
        rest = &rest[(end + 1).min(rest.len())..];
    }
    out.push_str(rest);
    Ok(out)
}

/// Removes every `ident::` qualifier.
fn strip(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    for (i, part) in line.split("::").enumerate() {
        if i > 0 {
            let keep = out
                .trim_end_matches(|c: char| c.is_ascii_alphanumeric() || c == '_')
                .len();
            out.truncate(keep);
        }
        out.push_str(part);
    }
    out
}

/// The `mcg::constants` source with only the named constants (all of them when `all`).
fn constants_subset(needs: &Needs) -> String {
    Module::Constants
        .source()
        .lines()
        .filter(|line| {
            let Some(rest) = line.strip_prefix("const ") else {
                return true;
            };
            let name = rest.split(':').next().unwrap_or("").trim();
            needs.all_constants || needs.constants.contains(name)
        })
        .fold(String::new(), |mut out, line| {
            out.push_str(line);
            out.push('\n');
            out
        })
}

fn library(needs: &Needs, defs: &[(&str, u32)]) -> Result<String, ShaderError> {
    let mut out = String::new();
    for module in Module::ALL {
        if !needs.modules.contains(&module) {
            continue;
        }
        let source = if module == Module::Constants {
            constants_subset(needs)
        } else {
            module.source().to_string()
        };
        out.push_str(&format!(
            "// ---- {} ({}) ----\n",
            module.import_path(),
            module.file_path()
        ));
        out.push_str(&preprocess(&source, module.file_path(), defs, false)?);
    }
    Ok(out)
}

/// The plain WGSL of `modules` and everything they import, each module exactly once, in
/// dependency order, with only the constants they use — to put before or after your own code.
/// `defs` gives the shader defs (see [`defs`](super::defs)) as name–value pairs.
///
/// # Errors
/// [`ShaderError::MissingShaderDef`] when a chosen module reads a def `defs` lacks.
///
/// # Example
/// ```
/// use mcg_gpu_backend::shaders::{Module, wgsl};
/// let library = wgsl(&[Module::Vmf], &[])?;
/// assert!(library.contains("fn vmf_sample_with_pdf(") && !library.contains("HASHGRID_"));
/// # Ok::<(), mcg_gpu_backend::shaders::ShaderError>(())
/// ```
pub fn wgsl(modules: &[Module], defs: &[(&str, u32)]) -> Result<String, ShaderError> {
    let mut needs = Needs::default();
    for &module in modules {
        if module == Module::Constants {
            needs.all_constants = true;
        }
        needs.add_module(module)?;
    }
    library(&needs, defs)
}

/// Your shader, written with naga_oil `#import mcg::…` lines, as plain WGSL: your lines first
/// with their numbers unchanged (directives become empty lines, qualifiers such as `vmf::` are
/// dropped, `#{DEF}` substituted), then the library modules it needs (see [`wgsl`]).
///
/// # Errors
/// [`ShaderError::UnknownImport`] for an import outside the library,
/// [`ShaderError::MissingShaderDef`] for a def a used module (or your code) reads and `defs`
/// lacks, [`ShaderError::UnbalancedConditional`] for broken `#ifdef`s.
pub fn compose(source: &str, defs: &[(&str, u32)]) -> Result<String, ShaderError> {
    let mut needs = Needs::default();
    needs.add_imports(source, YOUR_SHADER)?;
    let mut out = preprocess(source, YOUR_SHADER, defs, true)?;
    out.push_str(&library(&needs, defs)?);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_and_multi_line_imports_expand() {
        let src = "#import mcg::vmf::{Vmf, vmf_pdf}\n#import mcg::{\n  hashgrid::hashgrid_find_x,\n  math\n}\n#import mcg::sampling as S\n";
        let got: Vec<_> = imports(src).map(|i| (i.module, i.item, i.line)).collect();
        assert_eq!(
            got,
            vec![
                ("mcg::vmf".into(), Some("Vmf".into()), 1),
                ("mcg::vmf".into(), Some("vmf_pdf".into()), 1),
                ("mcg::hashgrid".into(), Some("hashgrid_find_x".into()), 2),
                ("mcg::math".into(), None, 2),
                ("mcg::sampling".into(), None, 6),
            ]
        );
    }

    #[test]
    fn preprocessing_keeps_line_numbers_and_strips_qualifiers() {
        let src = "#import mcg::vmf\n#ifdef A\nlet a = #{A};\n#else\nlet a = 0;\n#endif\nlet b = vmf::vmf_pdf(x);\n";
        let out = preprocess(src, "t", &[("A", 7)], true).unwrap();
        assert_eq!(out, "\n\nlet a = 7;\n\n\n\nlet b = vmf_pdf(x);\n");
        let out = preprocess(src, "t", &[], true).unwrap();
        assert_eq!(out, "\n\n\n\nlet a = 0;\n\nlet b = vmf_pdf(x);\n");
        assert_eq!(
            preprocess("#endif\n", "t", &[], true),
            Err(ShaderError::UnbalancedConditional {
                file: "t".into(),
                line: 1
            })
        );
        assert_eq!(
            preprocess("x #{B}\n", "t", &[], true),
            Err(ShaderError::MissingShaderDef {
                file: "t".into(),
                line: 1,
                def: "B".into()
            })
        );
    }

    #[test]
    fn unknown_imports_are_named() {
        let err = compose("\n#import bevy_pbr::mesh\n", &[]).unwrap_err();
        assert_eq!(
            err,
            ShaderError::UnknownImport {
                file: YOUR_SHADER.into(),
                line: 2,
                path: "bevy_pbr::mesh".into()
            }
        );
        assert!(err.to_string().contains("mcg::vmf"));
    }
}
