//! Resources that pass kinds create for their slots ([`crate::graph::Creates`]): a write slot
//! bound to a name the file does not declare gets a resource of that name, and a slot created
//! `always` that the file leaves unbound gets one named `pass.slot`. They join the declared
//! resources before the passes are checked, so that every pass, earlier ones included, binds
//! them by name, and from then on they are resources like any other (sizes, aliasing, barriers,
//! device limits, the plan).

use super::Validator;
use crate::graph::error::Pos;
use crate::graph::expr::{Expr, Num};
use crate::graph::kinds::{Created, Creates, Extent, MipChain, PassKindInfo, Unbound};
use crate::graph::locate::Seg;
use crate::graph::schema::{GraphFile, PassDecl};
use crate::graph::validated::{ImageSize, LocatedExpr, Mips, Owner, Resource, ResourceDesc};
use crate::graph::ResourceId;

/// A resource created for a slot that the file leaves unbound: the pass binds it implicitly.
pub(crate) struct ImplicitBinding {
    /// The slot.
    pub slot: &'static str,
    /// The resource created for it.
    pub resource: ResourceId,
}

impl Validator<'_> {
    /// Appends to `resources` (and `samples`) what the kinds of the file's passes create;
    /// returns, per pass, the slots bound implicitly.
    pub(super) fn created_resources(
        &mut self,
        file: &GraphFile,
        resources: &mut Vec<Resource>,
        samples: &mut Vec<u32>,
    ) -> Vec<Vec<ImplicitBinding>> {
        let mut implicit = Vec::with_capacity(file.passes.len());
        for (i, decl) in file.passes.iter().enumerate() {
            let mut bound_here = Vec::new();
            let Some(kind) = self.kinds.info(&decl.kind).filter(|k| !k.slots_from_shader) else {
                implicit.push(bound_here);
                continue;
            };
            for slot in &kind.writes {
                let Some(creates) = slot.creates else { continue };
                let written = decl.writes.0.iter().position(|(s, _)| s == slot.name);
                let (name, pos) = match written {
                    Some(j) => {
                        let name = &decl.writes.0[j].1;
                        // `.prev` here is an error reported with the pass's bindings.
                        if name.ends_with(".prev") || resources.iter().any(|r| &r.name == name) {
                            continue;
                        }
                        let at = [Seg::Field("passes"), Seg::Index(i), Seg::Field("writes"), Seg::Value(j)];
                        (name.clone(), self.pos(&at))
                    }
                    None if match creates.unbound {
                        Unbound::Nothing => false,
                        Unbound::Create => true,
                        Unbound::CreateWith(other) => {
                            decl.writes.0.iter().chain(&decl.reads.0).any(|(s, _)| s == other)
                        }
                    } =>
                    {
                        let name = format!("{}.{}", decl.name, slot.name);
                        if resources.iter().any(|r| r.name == name) {
                            continue;
                        }
                        (name, self.pos(&[Seg::Field("passes"), Seg::Index(i), Seg::Field("name")]))
                    }
                    None => continue,
                };
                let Some(desc) = self.created_desc(i, decl, kind, (slot.name, creates), (&name, pos), resources) else {
                    continue;
                };
                let owner = Owner { pass: i, pass_name: decl.name.clone(), slot: slot.name.to_string() };
                resources.push(Resource {
                    name,
                    pos,
                    desc,
                    history: creates.history,
                    imported: false,
                    owner: Some(owner),
                    when: None,
                });
                samples.push(1);
                if written.is_none() {
                    bound_here.push(ImplicitBinding { slot: slot.name, resource: resources.len() - 1 });
                }
            }
            implicit.push(bound_here);
        }
        implicit
    }

    /// The description of what `kind` creates for `slot` of pass `i`, or `None` (reported)
    /// when it is sized by a slot the pass leaves unbound.
    fn created_desc(
        &mut self,
        i: usize,
        decl: &PassDecl,
        kind: &PassKindInfo,
        (slot, creates): (&str, Creates),
        (name, pos): (&str, Pos),
        resources: &[Resource],
    ) -> Option<ResourceDesc> {
        let pass_pos = self.pos(&[Seg::Field("passes"), Seg::Index(i), Seg::Field("name")]);
        let constant = |n: i64| LocatedExpr::constant(Num::Int(n), pos);
        match creates.resource {
            Created::Buffer | Created::BufferOf(_) => {
                let text = match creates.resource {
                    Created::BufferOf(bytes) => bytes,
                    _ => kind.slot(slot).and_then(|s| s.bytes.expr()).unwrap_or("4"),
                };
                // The registry checked the expression when the kind was registered.
                let expr = Expr::parse(text).unwrap_or_else(|_| Expr::constant(Num::Int(4)));
                Some(ResourceDesc::Buffer { size: LocatedExpr { expr, pos, plain: false } })
            }
            Created::Image { format, extent, mips } => {
                let size = match extent {
                    Extent::Output => ImageSize::Output,
                    Extent::Of { slot: of, divisor } => {
                        let bound = decl.reads.0.iter().chain(&decl.writes.0).find(|(s, _)| s == of);
                        let base = bound.map(|(_, r)| r.strip_suffix(".prev").unwrap_or(r));
                        match base.and_then(|b| resources.iter().position(|r| r.name == b)) {
                            Some(resource) => ImageSize::Like { resource, divisor: divisor.max(1) },
                            None if bound.is_none() => {
                                self.err(
                                    pass_pos,
                                    format!(
                                        "pass '{}' creates '{name}' for its slot \"{slot}\" with the size of its \
                                         slot \"{of}\", which it does not bind",
                                        decl.name
                                    ),
                                );
                                return None;
                            }
                            // An unknown resource there is reported with the pass's bindings.
                            None => return None,
                        }
                    }
                };
                let mips = match mips {
                    MipChain::One => Mips::Count(constant(1)),
                    MipChain::All => Mips::All,
                };
                Some(ResourceDesc::Image { format, format_pos: pos, size, mips, samples: constant(1) })
            }
        }
    }
}
