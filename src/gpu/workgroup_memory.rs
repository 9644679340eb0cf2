//! How many bytes of workgroup (`shared`) memory a SPIR-V module declares, which the device
//! bounds by `maxComputeSharedMemorySize`. spirq does not reflect variables of the Workgroup
//! storage class, so the module's type and variable declarations are walked here.
//!
//! The count is conservative, so that a shader it accepts is one the device accepts: every
//! variable is laid out with the alignment that std430 would give it (a 3-component vector takes
//! the room of 4, an array element is padded to its alignment, a struct member to its own) and
//! the variables are added, none overlapping.

use spirq::spirv::{Op, StorageClass};
use std::collections::HashMap;

/// Size and alignment in bytes of a type.
#[derive(Clone, Copy)]
struct Layout {
    size: u64,
    align: u64,
}

fn round_up(value: u64, align: u64) -> u64 {
    value.div_ceil(align.max(1)).saturating_mul(align.max(1))
}

/// Bytes of workgroup memory that the variables of `spirv` take. `Err` names what could not be
/// sized (an array whose length is a specialization-constant expression, a type this walk does
/// not know): such a shader is refused rather than guessed.
pub fn workgroup_memory_bytes(spirv: &[u32]) -> Result<u64, String> {
    const HEADER_WORDS: usize = 5;
    let mut layouts: HashMap<u32, Layout> = HashMap::new();
    // Integer constants by id: array lengths.
    let mut constants: HashMap<u32, u64> = HashMap::new();
    // Pointer types to workgroup memory: pointer id -> pointee type id.
    let mut workgroup_pointers: HashMap<u32, u32> = HashMap::new();
    let mut total = 0u64;
    let mut at = HEADER_WORDS;
    while at < spirv.len() {
        let word_count = (spirv[at] >> 16) as usize;
        let Some(words) = spirv.get(at..at + word_count).filter(|_| word_count > 0) else {
            return Err(format!("malformed SPIR-V: an instruction at word {at} runs past the end"));
        };
        at += word_count;
        let Some(op) = Op::from_u32(words[0] & 0xffff) else { continue };
        let word = |i: usize| words.get(i).copied().unwrap_or(0);
        let result = word(1);
        // Types whose parts cannot be sized (images, runtime arrays, lengths from
        // specialization-constant expressions) get no layout; only a workgroup variable of
        // such a type is an error.
        let known = |id: u32| layouts.get(&id).copied();
        let layout = match op {
            // A bool has no size in memory; count it as a 32-bit integer.
            Op::TypeBool => Some(Layout { size: 4, align: 4 }),
            Op::TypeInt | Op::TypeFloat => {
                let bytes = (word(2) as u64 / 8).max(1);
                Some(Layout { size: bytes, align: bytes })
            }
            Op::TypeVector => known(word(2)).map(|component| {
                // vec3 takes the room (and alignment) of vec4.
                let count = if word(3) == 3 { 4 } else { word(3) as u64 };
                let size = component.size.saturating_mul(count);
                Layout { size, align: size.max(1) }
            }),
            Op::TypeMatrix => known(word(2)).map(|column| Layout {
                size: round_up(column.size, column.align).saturating_mul(word(3) as u64),
                align: column.align,
            }),
            Op::TypeArray => known(word(2)).zip(constants.get(&word(3))).map(|(element, &length)| Layout {
                size: round_up(element.size, element.align).saturating_mul(length),
                align: element.align,
            }),
            Op::TypeStruct => {
                let members: Option<Vec<Layout>> = words.get(2..).unwrap_or(&[]).iter().map(|&m| known(m)).collect();
                members.map(|members| {
                    let (mut offset, mut align) = (0u64, 1u64);
                    for m in members {
                        offset = round_up(offset, m.align).saturating_add(m.size);
                        align = align.max(m.align);
                    }
                    Layout { size: round_up(offset, align), align }
                })
            }
            Op::TypePointer => {
                if word(2) == StorageClass::Workgroup as u32 {
                    workgroup_pointers.insert(result, word(3));
                }
                Some(Layout { size: 8, align: 8 })
            }
            // The default value of a specialization constant is the one a pipeline created
            // without specialization uses.
            Op::Constant | Op::SpecConstant => {
                let value = word(3) as u64 | (words.get(4).map_or(0, |&w| w as u64) << 32);
                constants.insert(word(2), value);
                None
            }
            Op::Variable if word(3) == StorageClass::Workgroup as u32 => {
                let l = workgroup_pointers.get(&word(1)).and_then(|pointee| known(*pointee)).ok_or(
                    "a shared variable's size is not known at compile time (an array sized by a \
                     specialization-constant expression?)",
                )?;
                total = total.saturating_add(round_up(l.size, l.align));
                None
            }
            // Past the declarations: no more global variables.
            Op::Function => break,
            _ => None,
        };
        if let Some(layout) = layout {
            layouts.insert(result, layout);
        }
    }
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::{ShaderCompiler, ShaderRoot};

    /// The workgroup bytes of a compute shader declaring `decls` and touching `uses` (so that
    /// the optimizer keeps the variables).
    fn bytes(decls: &str, uses: &str) -> Result<u64, String> {
        let source = format!(
            "#version 460\nlayout(local_size_x = 64) in;\nlayout(binding = 0) buffer Out {{ float o[]; }};\n{decls}\n\
             void main() {{\n uint i = gl_LocalInvocationIndex;\n {uses}\n}}\n"
        );
        let compiler = ShaderCompiler::new(ShaderRoot::Embedded).unwrap();
        let spirv = compiler.compile_source("t.comp", &source, &[]).unwrap();
        workgroup_memory_bytes(&spirv)
    }

    #[test]
    fn counts_shared_variables_with_std430_padding() {
        assert_eq!(bytes("shared float a[4096];", "a[i] = 1.0; barrier(); o[i] = a[i ^ 1u];"), Ok(16384));
        assert_eq!(bytes("shared vec3 v[10];", "v[i % 10u] = vec3(1); barrier(); o[i] = v[i % 9u].y;"), Ok(160));
        assert_eq!(bytes("shared mat3 m;", "m[i % 3u] = vec3(i); barrier(); o[i] = m[1].y;"), Ok(48));
        assert_eq!(
            bytes(
                "struct S { vec3 a; float b; };\nshared S s[2];",
                "s[i % 2u].b = 1.0; s[i % 2u].a = vec3(2); barrier(); o[i] = s[1].b + s[0].a.x;"
            ),
            Ok(64)
        );
        assert_eq!(
            bytes("shared bool f;\nshared uint x;", "f = i == 3u; x = i; barrier(); o[i] = f ? float(x) : 0.0;"),
            Ok(8)
        );
        assert_eq!(bytes("", "o[i] = 1.0;"), Ok(0));
    }

    #[test]
    fn array_lengths_from_specialization_constants_take_their_default() {
        let decls = "layout(constant_id = 0) const uint N = 100;\nshared uint a[N];";
        assert_eq!(bytes(decls, "a[i % N] = i; barrier(); o[i] = float(a[(i + 1u) % N]);"), Ok(400));
        let decls = "layout(constant_id = 0) const uint N = 100;\nshared uint a[N * 2u];";
        let err = bytes(decls, "a[i] = i; barrier(); o[i] = float(a[i + 1u]);").unwrap_err();
        assert!(err.contains("not known at compile time"), "{err}");
    }
}
