//! Resource declarations: names, duplicates, formats, sizes, mips, sample counts.

use super::{Scope, Validator, Vars};
use crate::graph::compile::resolve;
use crate::graph::expr::Num;
use crate::graph::formats;
use crate::graph::locate::Seg;
use crate::graph::schema::{GraphFile, ImportedDecl, MipsDecl, NumLit, ResourceDecl, SizeDecl};
use crate::graph::validated::{ImageSize, LocatedExpr, Mips, Resource, ResourceDesc};
use ash::vk;

impl Validator<'_> {
    /// Resources in file order (duplicates left out) and each one's sample count (1 for buffers
    /// and where it could not be evaluated).
    pub(super) fn resources(&mut self, file: &GraphFile, scope: &Scope<'_>) -> (Vec<Resource>, Vec<u32>) {
        let mut out: Vec<Resource> = Vec::new();
        let mut samples_out = Vec::new();
        for (i, (name, decl)) in file.resources.0.iter().enumerate() {
            let pos = self.pos(&[Seg::Field("resources"), Seg::Key(i)]);
            if let Some(first) = out.iter().find(|r| &r.name == name) {
                let first = first.pos;
                self.err(pos, format!("duplicate resource '{name}' (first declared at {first})"));
                continue;
            }
            if name.is_empty() || !name.chars().all(|c| c.is_alphanumeric() || c == '_' || c == '-') {
                self.err(pos, format!("resource name '{name}' may only contain letters, digits, '_' and '-'"));
            }
            let (imported, history, when) = match decl {
                ResourceDecl::Image { history, when, .. } | ResourceDecl::Buffer { history, when, .. } => {
                    (false, *history, when.as_ref())
                }
                ResourceDecl::Imported(_) => (true, false, None),
            };
            let mut base = vec![Seg::Field("resources"), Seg::Value(i)];
            if imported {
                base.push(Seg::Index(0));
            }
            let image = match decl {
                ResourceDecl::Image { format, size, mips, samples, .. }
                | ResourceDecl::Imported(ImportedDecl::Image { format, size, mips, samples }) => {
                    Some((format, size, mips, samples))
                }
                _ => None,
            };
            let (desc, samples) = match (image, decl) {
                (Some((format, size, mips, samples)), _) => self.image(name, &base, format, size, mips, samples, scope),
                (None, ResourceDecl::Buffer { size, .. } | ResourceDecl::Imported(ImportedDecl::Buffer { size })) => {
                    (self.buffer(name, &base, size, scope), 1)
                }
                (None, _) => continue,
            };
            let when = when.and_then(|w| {
                let path = [base.as_slice(), &[Seg::Field("when")]].concat();
                self.num(w, &path, &format!("condition of resource '{name}'"), scope, Vars::Frame)
            });
            out.push(Resource { name: name.clone(), pos, desc, history, imported, owner: None, when });
            samples_out.push(samples);
        }
        (out, samples_out)
    }

    fn buffer(&mut self, name: &str, base: &[Seg<'static>], size: &NumLit, scope: &Scope<'_>) -> ResourceDesc {
        let path = [base, &[Seg::Field("size")]].concat();
        let what = format!("size of buffer '{name}'");
        let size = match self.num(size, &path, &what, scope, Vars::Frame) {
            Some(e) => {
                self.check_now(&e, scope, &what, resolve::buffer_bytes);
                e
            }
            None => LocatedExpr::constant(Num::Int(4), self.pos(&path)),
        };
        ResourceDesc::Buffer { size }
    }

    #[allow(clippy::too_many_arguments)]
    fn image(
        &mut self,
        name: &str,
        base: &[Seg<'static>],
        format: &crate::graph::schema::FormatName,
        size: &SizeDecl,
        mips: &Option<MipsDecl>,
        samples: &Option<NumLit>,
        scope: &Scope<'_>,
    ) -> (ResourceDesc, u32) {
        let format_path = [base, &[Seg::Field("format")]].concat();
        let format_pos = self.pos(&format_path);
        let vk_format = match formats::by_name(&format.0) {
            Some(f) => f.format,
            None => {
                let close = formats::suggestions(&format.0, 3).join(", ");
                self.err(format_pos, format!("unknown format '{}' (close: {close})", format.0));
                vk::Format::UNDEFINED
            }
        };
        let size_path = [base, &[Seg::Field("size")]].concat();
        let one = |pos| LocatedExpr::constant(Num::Int(1), pos);
        let size = match size {
            SizeDecl::Output => ImageSize::Output,
            SizeDecl::Scaled(f) => {
                let path = [size_path.as_slice(), &[Seg::Index(0)]].concat();
                let what = format!("scale of image '{name}'");
                match self.num(f, &path, &what, scope, Vars::Frame) {
                    Some(e) => {
                        self.check_now(&e, scope, &what, resolve::scale);
                        ImageSize::Scaled(e)
                    }
                    None => ImageSize::Output,
                }
            }
            SizeDecl::Fixed(w, h) => {
                let mut dim = |lit: &NumLit, index: usize, axis: &str| {
                    let path = [size_path.as_slice(), &[Seg::Index(index)]].concat();
                    let what = format!("{axis} of image '{name}'");
                    match self.num(lit, &path, &what, scope, Vars::Frame) {
                        Some(e) => {
                            self.check_now(&e, scope, &what, resolve::image_dimension);
                            e
                        }
                        None => one(self.pos(&path)),
                    }
                };
                let w = dim(w, 0, "width");
                let h = dim(h, 1, "height");
                ImageSize::Fixed(w, h)
            }
        };
        let mips_path = [base, &[Seg::Field("mips")]].concat();
        let mips = match mips {
            None => Mips::Count(one(self.pos(base))),
            Some(MipsDecl::Named) => {
                let written = self.src.ident(&mips_path).unwrap_or("").to_string();
                if written != "All" {
                    self.err(
                        self.pos(&mips_path),
                        format!("mips of image '{name}' must be All, a number or an expression, not '{written}'"),
                    );
                }
                Mips::All
            }
            Some(MipsDecl::Count(lit)) => {
                let what = format!("mips of image '{name}'");
                match self.num(lit, &mips_path, &what, scope, Vars::Frame) {
                    Some(e) => {
                        // The upper bound depends on the size, known when compiling.
                        self.check_now(&e, scope, &what, |n| match n.as_whole() {
                            Some(v) if v >= 1 => Ok(()),
                            _ => Err(format!("is {n} (must be a whole number, at least 1)")),
                        });
                        Mips::Count(e)
                    }
                    None => Mips::Count(one(self.pos(&mips_path))),
                }
            }
        };
        let samples_path = [base, &[Seg::Field("samples")]].concat();
        let what = format!("samples of image '{name}'");
        let (samples, count) = match samples {
            None => (one(self.pos(base)), 1),
            Some(lit) => match self.num(lit, &samples_path, &what, scope, Vars::ParamsOnly) {
                Some(e) => {
                    let n = self.check_now(&e, scope, &what, resolve::sample_count).unwrap_or(1);
                    (e, n)
                }
                None => (one(self.pos(&samples_path)), 1),
            },
        };
        (ResourceDesc::Image { format: vk_format, format_pos, size, mips, samples }, count)
    }

    /// Evaluates `e` now if it uses params only, and reports a value `check` refuses.
    pub(super) fn check_now<T>(
        &mut self,
        e: &LocatedExpr,
        scope: &Scope<'_>,
        what: &str,
        check: impl Fn(Num) -> Result<T, String>,
    ) -> Option<T> {
        if e.expr.variables().iter().any(|(v, _)| scope.param(v).is_none()) {
            return None;
        }
        match resolve::eval(e, &scope.param_values()) {
            Ok(n) => match check(n) {
                Ok(v) => Some(v),
                Err(m) => {
                    self.err(e.pos, format!("{what} {m}"));
                    None
                }
            },
            Err((pos, m)) => {
                self.err(pos, format!("{what}: {m}"));
                None
            }
        }
    }
}
