//! Build script: links Debian's static glslang/SPIRV-Tools archives for shaderc and embeds `shaders/`.
//!
//! Debian's `libshaderc_combined.a` holds only shaderc itself and its `libshaderc.so` is under-linked,
//! so on Debian-like hosts we add the static glslang and SPIRV-Tools archives (see
//! `docs/building.md`). Other hosts (a Vulkan SDK, a fat `libshaderc_combined.a`) skip this.
use std::{env, fs, path::Path};

const DEBIAN_LIB_DIR: &str = "/usr/lib/x86_64-linux-gnu";
const DEBIAN_STATIC_LIBS: &[&str] = &[
    "glslang",
    "MachineIndependent",
    "OSDependent",
    "GenericCodeGen",
    "OGLCompiler",
    "HLSL",
    "SPIRV",
    "SPIRV-Tools-opt",
    "SPIRV-Tools",
    "glslang-default-resource-limits",
];

fn main() {
    println!("cargo:rerun-if-env-changed=SHADERC_DEBIAN_STATIC");
    let forced = env::var("SHADERC_DEBIAN_STATIC").map(|v| v == "1").unwrap_or(false);
    let debian = Path::new(DEBIAN_LIB_DIR).join("libMachineIndependent.a").exists();
    if forced || debian {
        println!("cargo:rustc-link-search=native={DEBIAN_LIB_DIR}");
        for lib in DEBIAN_STATIC_LIBS {
            println!("cargo:rustc-link-lib=static={lib}");
        }
    }
    embed_shaders();
}

/// Writes `$OUT_DIR/embedded_shaders.rs`: every file under `shaders/` as `(relative path, source)`,
/// so a binary carried to another machine compiles its shaders without the source tree.
fn embed_shaders() {
    // The manifest dir at run time of the script: env!() would freeze the dir it was compiled in.
    let manifest = env::var("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR is set by cargo");
    let root = Path::new(&manifest).join("shaders");
    println!("cargo:rerun-if-changed={}", root.display());
    let mut files = Vec::new();
    collect(&root, &root, &mut files);
    files.sort();
    let mut out = String::from("/// Shader sources embedded at build time: (path relative to `shaders/`, text).\n");
    out.push_str("pub static EMBEDDED_SHADERS: &[(&str, &str)] = &[\n");
    for rel in &files {
        let abs = root.join(rel);
        println!("cargo:rerun-if-changed={}", abs.display());
        out.push_str(&format!("    ({rel:?}, include_str!({:?})),\n", abs.display().to_string()));
    }
    out.push_str("];\n");
    let dest = Path::new(&env::var("OUT_DIR").expect("OUT_DIR is set by cargo")).join("embedded_shaders.rs");
    fs::write(dest, out).expect("write embedded_shaders.rs");
}

fn collect(root: &Path, dir: &Path, files: &mut Vec<String>) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            println!("cargo:rerun-if-changed={}", path.display());
            collect(root, &path, files);
        } else if let Ok(rel) = path.strip_prefix(root) {
            files.push(rel.to_string_lossy().replace('\\', "/"));
        }
    }
}
