//! WGSL sources put together by one typed builder instead of strings joined in a hand-kept
//! order. A shared file is a [`Module`] that names the modules it needs (and says so in
//! its own `// Needs:` line, checked against the Rust side by the tests); a [`Source`]
//! includes each module once, after what it needs, and takes the constants a pass is
//! compiled with as [`Source::define`]s rather than text pasted in by `format!`.

use std::fmt::Write;

/// A WGSL file shared by several shaders, and the modules it calls into.
#[derive(Debug)]
pub struct Module {
    /// Its path under `shaders/`, without `.wgsl` (what its `// Needs:` lines name).
    pub name: &'static str,
    pub text: &'static str,
    pub needs: &'static [&'static Module],
}

/// A value a pass is compiled with: its WGSL type and literal.
pub trait Define {
    fn wgsl(&self) -> (&'static str, String);
}

impl Define for bool {
    fn wgsl(&self) -> (&'static str, String) {
        ("bool", self.to_string())
    }
}

impl Define for u32 {
    fn wgsl(&self) -> (&'static str, String) {
        ("u32", format!("{self}u"))
    }
}

/// A shader being put together: its defines, then its parts in the order added (each
/// module once, its needs first), then the pass itself ([`Source::pass`]).
#[derive(Default)]
pub struct Source {
    defines: String,
    parts: Vec<String>,
    included: Vec<&'static str>,
}

impl Source {
    pub fn new() -> Source {
        Source::default()
    }

    /// `const NAME: type = value;` at the top.
    pub fn define(mut self, name: &str, value: impl Define) -> Source {
        let (ty, literal) = value.wgsl();
        let _ = writeln!(self.defines, "const {name}: {ty} = {literal};");
        self
    }

    /// `module`, after the modules it needs; nothing if it is already in.
    pub fn module(mut self, module: &'static Module) -> Source {
        self.include(module);
        self
    }

    fn include(&mut self, module: &'static Module) {
        if self.included.contains(&module.name) {
            return;
        }
        for need in module.needs {
            self.include(need);
        }
        self.included.push(module.name);
        self.parts.push(module.text.to_string());
    }

    /// Text made at run time (codes, the registry's dispatch), added where it stands.
    pub fn generated(mut self, text: String) -> Source {
        self.parts.push(text);
        self
    }

    /// The whole source, ending with `pass`.
    pub fn pass(self, pass: &str) -> String {
        let mut out = self.defines;
        for part in self.parts {
            out += &part;
            out.push('\n');
        }
        out + pass
    }
}

/// The modules a file's `// Needs:` lines name (comma- or "and"-separated paths under
/// `shaders/`, with or without `.wgsl`), in order.
pub fn declared_needs(text: &str) -> Vec<String> {
    text.lines()
        .take_while(|l| l.starts_with("//"))
        .filter_map(|l| l.trim_start_matches('/').trim().strip_prefix("Needs:"))
        .flat_map(|list| {
            list.split([',', ' '])
                .map(|w| w.trim().trim_end_matches('.').trim_end_matches(".wgsl"))
                .filter(|w| !w.is_empty() && *w != "and")
                .map(str::to_string)
                .collect::<Vec<_>>()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    static A: Module = Module {
        name: "a",
        text: "fn a() {}",
        needs: &[],
    };
    static B: Module = Module {
        name: "b",
        text: "fn b() { a(); }",
        needs: &[&A],
    };
    static C: Module = Module {
        name: "c",
        text: "fn c() { a(); b(); }",
        needs: &[&B, &A],
    };

    /// Each module once, after what it needs; defines first, the pass last.
    #[test]
    fn modules_come_once_after_their_needs() {
        let src = Source::new()
            .define("FLAG", true)
            .module(&C)
            .module(&A)
            .define("N", 3u32)
            .pass("fn main() {}");
        assert_eq!(
            src,
            "const FLAG: bool = true;\nconst N: u32 = 3u;\nfn a() {}\nfn b() { a(); }\nfn c() { a(); b(); }\nfn main() {}"
        );
    }

    #[test]
    fn needs_lines_are_read() {
        let text =
            "// A module.\n// Needs: sim/math and sim/svd.wgsl.\nfn f() {}\n// Needs: not a header";
        assert_eq!(declared_needs(text), ["sim/math", "sim/svd"]);
    }
}
