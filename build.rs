//! Compiles every `glsl/**/*.comp` to SPIR-V with glslang and writes the words
//! into `$OUT_DIR/shaders.rs` as `u32` arrays, so the binary needs no shader
//! files and the SPIR-V is 4-byte aligned by construction. Beside the words
//! goes each shader's interface read from the SPIR-V (`build/reflect.rs`):
//! named bindings, push-constant size, workgroup size, from which kernels
//! are created; and its host side, generated: a module per kernel with its
//! push block as a `#[repr(C)]` struct (`Push`) and its bindings as a struct
//! of named fields (`Bindings`; march kernels `Own`), `MarchCommon` (the
//! bindings every march kernel has), and `blocks` (the structs the host lays
//! out in GPU memory, checked alike across the shaders that declare them).

use glslang::include::{IncludeHandler, IncludeResult, IncludeType};
use glslang::{
    Compiler, CompilerOptions, ShaderInput, ShaderMessage, ShaderSource, ShaderStage, SourceLanguage, SpirvVersion,
    Target, VulkanVersion,
};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[path = "build/reflect.rs"]
mod reflect;

#[cfg(feature = "mpi")]
#[path = "build/mpi.rs"]
mod mpi;

/// Resolves `#include "x.glsl"` against `glsl/common/` (and the including
/// file's own folder), recording every file it opens for `rerun-if-changed`.
struct Includer {
    dirs: Vec<PathBuf>,
    opened: Vec<PathBuf>,
    missing: Vec<String>,
}

impl IncludeHandler for Includer {
    fn include(&mut self, _ty: IncludeType, header: &str, _includer: &str, _depth: usize) -> Option<IncludeResult> {
        for dir in &self.dirs {
            let path = dir.join(header);
            if let Ok(data) = std::fs::read_to_string(&path) {
                self.opened.push(path);
                return Some(IncludeResult {
                    name: header.to_string(),
                    data,
                });
            }
        }
        self.missing.push(header.to_string());
        None
    }
}

fn collect(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect(&path, ext, out);
        } else if path.extension().is_some_and(|e| e == ext) {
            out.push(path);
        }
    }
}

/// glslang names the top-level source "0"; point messages at the real file.
fn locate(log: &str, file: &str) -> String {
    log.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.replace(" 0:", &format!(" {file}:")))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Structs the host reads or writes in GPU memory, generated once into
/// `shaders::blocks` from every shader that declares them (which must agree):
/// the render parameter block and the node and primitive formats.
const SHARED_STRUCTS: [&str; 5] = ["RenderParams", "BvhNode", "OctNode", "Prim", "TraceRay"];

/// The bindings every march kernel has (`glsl/common/march.glsl`); the
/// renderer binds them, the structure the rest.
const MARCH_COMMON: [&str; 13] = [
    "params",
    "volume_tex",
    "tf_lut",
    "frame",
    "frame_depth",
    "gradient_tex",
    "volume_cells",
    "gradient_cells",
    "brick_table",
    "pool_1",
    "pool_2",
    "pool_3",
    "march_status",
];

/// Rust keywords a GLSL name may collide with.
fn ident(name: &str) -> String {
    const KEYWORDS: [&str; 12] = [
        "type", "ref", "in", "box", "loop", "match", "mod", "move", "self", "use", "where", "impl",
    ];
    if KEYWORDS.contains(&name) {
        format!("r#{name}")
    } else {
        name.to_string()
    }
}

/// A `#[repr(C)]` Pod struct with the shader's layout; gaps become `_padN`
/// words so the layout is exact and every byte is initialised.
fn rust_struct(doc: &str, name: &str, def: &reflect::Struct) -> Result<String, String> {
    let mut out = format!(
        "/// {doc}\n#[repr(C)]\n#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]\npub struct {name} {{\n"
    );
    let mut cursor = 0;
    for (k, m) in def.members.iter().enumerate() {
        if m.offset < cursor || (m.offset - cursor) % 4 != 0 {
            return Err(format!(
                "{}.{}: offset {} has no Rust layout",
                def.name, m.name, m.offset
            ));
        }
        if m.offset > cursor {
            let _ = writeln!(out, "    pub _pad{k}: [u32; {}],", (m.offset - cursor) / 4);
        }
        let _ = writeln!(out, "    pub {}: {},", ident(&m.name), m.rust);
        cursor = m.offset + m.size;
    }
    let _ = writeln!(
        out,
        "}}\nimpl Default for {name} {{\n    fn default() -> Self {{\n        bytemuck::Zeroable::zeroed()\n    }}\n}}\nconst _: () = assert!(std::mem::size_of::<{name}>() == {});\n",
        def.size
    );
    Ok(out)
}

/// `pub mod <kernel>`: its push block as `Push`, and its bindings as a
/// struct of named fields (`Bindings`; march kernels: `Own`, the bindings
/// besides [`MARCH_COMMON`]) whose `list` gives them to `Kernel::dispatch`.
fn interface_module(
    stem: &str,
    rel: &str,
    iface: &reflect::Interface,
    is_march: bool,
    pushes: &mut Vec<(String, reflect::Struct)>,
) -> Result<String, String> {
    let module = stem.replace('/', "_");
    let mut out = format!("/// The host side of `glsl/{rel}`'s interface, generated from its SPIR-V.\npub mod {module} {{\n    #[allow(unused_imports)]\n    use super::*;\n");
    if let Some(push) = &iface.push {
        let same = |d: &reflect::Struct| d.members == push.members && d.size == push.size;
        if let Some((first, _)) = pushes.iter().find(|(_, d)| same(d)) {
            let _ = writeln!(
                out,
                "    /// The push-constant block, laid out as `{first}`'s.\n    pub use super::{first}::Push;"
            );
        } else {
            for line in rust_struct("The push-constant block.", "Push", push)?.lines() {
                let _ = writeln!(out, "    {line}");
            }
            pushes.push((module.clone(), push.clone()));
        }
    }
    let own: Vec<&reflect::Slot> = if is_march {
        for common in MARCH_COMMON {
            if !iface.bindings.iter().any(|b| b.name == common) {
                return Err(format!(
                    "a march kernel must declare the binding {common} (include march.glsl)"
                ));
            }
        }
        iface
            .bindings
            .iter()
            .filter(|b| !MARCH_COMMON.contains(&b.name.as_str()))
            .collect()
    } else {
        iface.bindings.iter().collect()
    };
    let what = if is_march { "Own" } else { "Bindings" };
    let doc = if is_march {
        "The kernel's own bindings (the renderer binds the common ones)."
    } else {
        "Every binding of the kernel, by name."
    };
    let _ = writeln!(out, "    /// {doc}\n    pub struct {what}<'a> {{");
    for b in &own {
        let _ = writeln!(out, "        pub {}: Binding<'a>,", ident(&b.name));
    }
    if own.is_empty() {
        out.push_str("        pub _none: std::marker::PhantomData<&'a ()>,\n");
    }
    let _ = writeln!(
        out,
        "    }}\n    impl<'a> {what}<'a> {{\n        /// (name, resource) pairs for `Kernel::dispatch`.\n        pub fn list(self) -> Vec<(&'static str, Binding<'a>)> {{\n            vec![{}]\n        }}\n    }}\n}}\n",
        own.iter()
            .map(|b| format!("({:?}, self.{})", b.name, ident(&b.name)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(out)
}

/// `MarchCommon`: the bindings every march kernel has, which the renderer
/// fills for whichever kernel marches.
fn march_common() -> String {
    let fields: Vec<String> = MARCH_COMMON
        .iter()
        .map(|n| format!("    pub {n}: Binding<'a>,"))
        .collect();
    let list: Vec<String> = MARCH_COMMON.iter().map(|n| format!("({n:?}, self.{n})")).collect();
    format!(
        "/// The bindings every march kernel has (`glsl/common/march.glsl`); a\n/// structure's own are its kernel's `Own`.\npub struct MarchCommon<'a> {{\n{}\n}}\nimpl<'a> MarchCommon<'a> {{\n    /// (name, resource) pairs for `Kernel::dispatch`.\n    pub fn list(self) -> Vec<(&'static str, Binding<'a>)> {{\n        vec![{}]\n    }}\n}}\n",
        fields.join("\n"),
        list.join(", ")
    )
}

/// `pub mod blocks`: the [`SHARED_STRUCTS`], each checked to be laid out
/// alike by every shader that declares it.
fn shared_module(shared: &[(String, reflect::Struct)]) -> Result<String, String> {
    let mut out = String::from(
        "/// Structs the host reads or writes in GPU memory, generated from the SPIR-V.\npub mod blocks {\n",
    );
    for name in SHARED_STRUCTS {
        let mut defs = shared.iter().filter(|(_, d)| d.name == name);
        let (first_file, first) = defs.next().ok_or(format!("no shader declares struct {name}"))?;
        if let Some((file, _)) = defs.find(|(_, d)| d != first) {
            return Err(format!(
                "struct {name} is laid out differently in glsl/{first_file} and glsl/{file}"
            ));
        }
        for line in rust_struct(&format!("`{name}` as the shaders lay it out."), name, first)?.lines() {
            let _ = writeln!(out, "    {line}");
        }
    }
    out.push_str("}\n");
    Ok(out)
}

/// Storage-image formats of host frames (GLSL format qualifiers).
const IMAGE_FORMATS: [&str; 3] = ["rgba8", "rgba16f", "rgba32f"];

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    let glsl = root.join("glsl");
    let common = glsl.join("common");
    println!("cargo:rerun-if-changed=glsl");
    println!("cargo:rerun-if-changed=build/reflect.rs");
    #[cfg(feature = "mpi")]
    mpi::build(&root);

    let mut shaders = Vec::new();
    collect(&glsl, "comp", &mut shaders);
    let mut headers = Vec::new();
    collect(&glsl, "glsl", &mut headers);
    for h in &headers {
        println!("cargo:rerun-if-changed={}", h.display());
    }

    let compiler = Compiler::acquire().expect("glslang compiler");
    let options = CompilerOptions {
        source_language: SourceLanguage::GLSL,
        target: Target::Vulkan {
            version: VulkanVersion::Vulkan1_3,
            spirv_version: SpirvVersion::SPIRV1_6,
        },
        version_profile: None,
        messages: ShaderMessage::DEFAULT | ShaderMessage::VULKAN_RULES | ShaderMessage::SPV_RULES,
    };

    let mut generated = String::from("// Generated by build.rs from glsl/**/*.comp. Do not edit.\n\n");
    let mut names = Vec::new();
    let mut failures = Vec::new();
    let mut shared: Vec<(String, reflect::Struct)> = Vec::new();
    // Push blocks generated so far, by module: a kernel whose block is laid
    // out and named exactly as an earlier kernel's shares its type.
    let mut pushes: Vec<(String, reflect::Struct)> = Vec::new();
    // March kernels are also compiled once per host storage-image format
    // (FRAME_FORMAT: glsl/common/frame_out.glsl), named `march/NAME@FORMAT`.
    let mut jobs: Vec<(&PathBuf, Option<&str>)> = Vec::new();
    for path in &shaders {
        jobs.push((path, None));
        if path.parent().is_some_and(|p| p.ends_with("march")) {
            for format in IMAGE_FORMATS {
                jobs.push((path, Some(format)));
            }
        }
    }
    for (path, format) in jobs {
        println!("cargo:rerun-if-changed={}", path.display());
        let rel = path.strip_prefix(&glsl).unwrap().to_string_lossy().replace('\\', "/");
        let stem = rel.trim_end_matches(".comp");
        let (kernel, name) = match format {
            None => (stem.to_string(), stem.replace('/', "_").to_uppercase()),
            Some(f) => (
                format!("{stem}@{f}"),
                format!("{stem}_{f}").replace('/', "_").to_uppercase(),
            ),
        };
        let defines = format.map(|f| [("FRAME_FORMAT", Some(f))]);
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let source = ShaderSource::from(text);
        let mut includer = Includer {
            dirs: vec![path.parent().unwrap().to_path_buf(), common.clone()],
            opened: Vec::new(),
            missing: Vec::new(),
        };
        let result = (|| {
            let input = ShaderInput::new(
                &source,
                ShaderStage::Compute,
                &options,
                defines.as_ref().map(|d| &d[..]),
                Some(&mut includer as &mut dyn IncludeHandler),
            )
            .map_err(|e| e.to_string())?;
            let shader = compiler.create_shader(input).map_err(|e| e.to_string())?;
            // Any message at all (warnings included) fails the build.
            let log = shader.get_log();
            if !log.trim().is_empty() {
                return Err(log);
            }
            shader.compile().map_err(|e| e.to_string())
        })();
        match result.and_then(|words| reflect::reflect(&words).map(|i| (words, i))) {
            Ok((words, iface)) => {
                let _ = writeln!(generated, "static {name}_WORDS: [u32; {}] = [", words.len());
                for chunk in words.chunks(8) {
                    let line: Vec<String> = chunk.iter().map(|w| format!("{w:#010x}")).collect();
                    let _ = writeln!(generated, "    {},", line.join(", "));
                }
                generated.push_str("];\n");
                let slots: Vec<String> = iface
                    .bindings
                    .iter()
                    .map(|b| {
                        format!(
                            "Slot {{ name: {:?}, ty: vk::DescriptorType::{}, block_size: {}, writes: {} }}",
                            b.name,
                            b.ty.vk_name(),
                            b.block_size,
                            b.writes
                        )
                    })
                    .collect();
                let dims: Vec<String> = iface
                    .local_size
                    .iter()
                    .map(|d| match d {
                        reflect::Dim::Fixed(n) => format!("LocalDim::Fixed({n})"),
                        reflect::Dim::Spec { id, default } => {
                            format!("LocalDim::Spec {{ id: {id}, default: {default} }}")
                        }
                    })
                    .collect();
                let _ = writeln!(
                    generated,
                    "/// `glsl/{rel}`: SPIR-V and its reflected interface.\npub const {name}: Shader = Shader {{\n    name: \"{kernel}\",\n    words: &{name}_WORDS,\n    bindings: &[{}],\n    push_size: {},\n    local_size: [{}],\n}};\n",
                    slots.join(", "),
                    iface.push_size,
                    dims.join(", ")
                );
                if format.is_none() {
                    let is_march = stem.starts_with("march/");
                    match interface_module(stem, &rel, &iface, is_march, &mut pushes) {
                        Ok(module) => generated.push_str(&module),
                        Err(e) => failures.push(format!("glsl/{rel}: {e}")),
                    }
                }
                for def in iface.structs {
                    if SHARED_STRUCTS.contains(&def.name.as_str()) {
                        shared.push((rel.clone(), def));
                    }
                }
                names.push((rel.clone(), name));
            }
            Err(log) => {
                let mut msg = locate(&log, &format!("glsl/{rel}"));
                includer.missing.dedup();
                for m in &includer.missing {
                    let _ = write!(
                        msg,
                        "\nglsl/{rel}: cannot resolve #include \"{m}\" (searched its folder and glsl/common)"
                    );
                }
                failures.push(msg);
            }
        }
    }
    if !failures.is_empty() {
        for f in &failures {
            println!("cargo:warning={}", f.replace('\n', " | "));
        }
        panic!("GLSL compilation failed:\n{}", failures.join("\n"));
    }
    match shared_module(&shared) {
        Ok(module) => generated.push_str(&module),
        Err(e) => panic!("GLSL interface types: {e}"),
    }
    generated.push_str(&march_common());
    generated.push_str("/// Every embedded shader.\npub static ALL: &[Shader] = &[\n");
    for (_, name) in &names {
        let _ = writeln!(generated, "    {name},");
    }
    generated.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("shaders.rs");
    std::fs::write(out, generated).unwrap();
    example_shaders(compiler, &options, &root);
}

/// The embedding example's raster shaders (`examples/embed/*.vert`,
/// `*.frag`): a host engine's own, so words only, into `example_shaders.rs`.
fn example_shaders(compiler: &Compiler, options: &CompilerOptions, root: &Path) {
    let mut generated = String::from("// Generated by build.rs from examples/embed/*.vert|frag. Do not edit.\n\n");
    for (file, stage) in [("mesh.vert", ShaderStage::Vertex), ("mesh.frag", ShaderStage::Fragment)] {
        let path = root.join("examples/embed").join(file);
        println!("cargo:rerun-if-changed={}", path.display());
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let source = ShaderSource::from(text);
        let words = ShaderInput::new(&source, stage, options, None, None)
            .map_err(|e| e.to_string())
            .and_then(|input| compiler.create_shader(input).map_err(|e| e.to_string()))
            .and_then(|shader| shader.compile().map_err(|e| e.to_string()))
            .unwrap_or_else(|e| panic!("examples/embed/{file}: {e}"));
        let name = file.replace('.', "_").to_uppercase();
        let _ = writeln!(generated, "pub static {name}: [u32; {}] = {words:?};", words.len());
    }
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("example_shaders.rs");
    std::fs::write(out, generated).unwrap();
}
