//! Reads a compute shader's interface from its SPIR-V words: descriptor
//! bindings of set 0 with their names and types, the push-constant block
//! (its members, offsets and types), the fixed members of storage and
//! uniform blocks and of the structs they hold, and the workgroup size
//! (literal or specialization constants). Only the few instructions that
//! carry these are decoded; names come from the debug names glslang emits.

use std::collections::HashMap;

/// Descriptor types lacuna's kernels use, by `vk::DescriptorType` constant name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Descriptor {
    UniformBuffer,
    StorageBuffer,
    CombinedImageSampler,
    StorageImage,
    SampledImage,
    /// `samplerBuffer`: a buffer read through a buffer view's format.
    UniformTexelBuffer,
}

impl Descriptor {
    pub fn vk_name(self) -> &'static str {
        match self {
            Descriptor::UniformBuffer => "UNIFORM_BUFFER",
            Descriptor::StorageBuffer => "STORAGE_BUFFER",
            Descriptor::CombinedImageSampler => "COMBINED_IMAGE_SAMPLER",
            Descriptor::StorageImage => "STORAGE_IMAGE",
            Descriptor::SampledImage => "SAMPLED_IMAGE",
            Descriptor::UniformTexelBuffer => "UNIFORM_TEXEL_BUFFER",
        }
    }
}

/// One workgroup dimension: a literal, or a specialization constant with its default.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    Fixed(u32),
    Spec { id: u32, default: u32 },
}

/// One binding of set 0.
pub struct Slot {
    /// The variable's name, or (an anonymous block) its block's name in snake_case.
    pub name: String,
    pub ty: Descriptor,
    /// The block size in bytes of a uniform or storage buffer (of a storage
    /// block ending in a runtime array, the part before it), else 0.
    pub block_size: u32,
    /// Whether the shader may write it: a storage buffer not declared
    /// `readonly` (NonWritable), or a storage image.
    pub writes: bool,
}

/// A struct as the shader lays it out (the fixed members of a block).
#[derive(Clone, Debug, PartialEq)]
pub struct Struct {
    pub name: String,
    pub members: Vec<Member>,
    /// Bytes up to the end of the last fixed member.
    pub size: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Member {
    pub name: String,
    pub offset: u32,
    /// The Rust type with this layout (`u32`, `[f32; 4]`, another struct's name).
    pub rust: String,
    pub size: u32,
}

pub struct Interface {
    /// Bindings 0.. of set 0, in order.
    pub bindings: Vec<Slot>,
    pub push_size: u32,
    /// The push-constant block, if any.
    pub push: Option<Struct>,
    /// Every named struct reachable from a uniform or storage block (the
    /// blocks' own types included), by name.
    pub structs: Vec<Struct>,
    pub local_size: [Dim; 3],
}

#[derive(Clone, Debug)]
enum Ty {
    /// Bytes, signedness.
    Int(u32, bool),
    /// Bytes.
    Float(u32),
    Vector(u32, u32),
    Matrix(u32, u32),
    Array(u32, u32),
    /// Of the element type with this id.
    RuntimeArray(u32),
    Struct(Vec<u32>),
    Image {
        dim: u32,
        sampled: u32,
    },
    /// Of the image type with this id.
    SampledImage(u32),
    Pointer(u32),
    Other,
}

#[derive(Default)]
struct Module {
    types: HashMap<u32, Ty>,
    constants: HashMap<u32, u32>,
    spec_ids: HashMap<u32, u32>,
    composites: HashMap<u32, Vec<u32>>,
    decorations: HashMap<(u32, u32), Vec<u32>>,
    member_offsets: HashMap<(u32, u32), u32>,
    /// Struct members decorated NonWritable (GLSL `readonly` on a block).
    nonwritable_members: std::collections::HashSet<(u32, u32)>,
    array_strides: HashMap<u32, u32>,
    variables: Vec<(u32, u32, u32)>,
    names: HashMap<u32, String>,
    member_names: HashMap<(u32, u32), String>,
    local_size: Option<[u32; 3]>,
    local_size_ids: Option<[u32; 3]>,
}

const DEC_SPEC_ID: u32 = 1;
const DEC_BLOCK: u32 = 2;
const DEC_BUFFER_BLOCK: u32 = 3;
const DEC_ARRAY_STRIDE: u32 = 6;
const DEC_BUILTIN: u32 = 11;
const DEC_NON_WRITABLE: u32 = 24;
const DEC_BINDING: u32 = 33;
const DEC_SET: u32 = 34;
const DEC_OFFSET: u32 = 35;
const BUILTIN_WORKGROUP_SIZE: u32 = 25;
/// OpTypeImage's Dim of a texel buffer.
const DIM_BUFFER: u32 = 5;
const SC_UNIFORM_CONSTANT: u32 = 0;
const SC_UNIFORM: u32 = 2;
const SC_PUSH_CONSTANT: u32 = 9;
const SC_STORAGE_BUFFER: u32 = 12;

impl Module {
    fn parse(words: &[u32]) -> Result<Module, String> {
        if words.len() < 5 || words[0] != 0x0723_0203 {
            return Err("not SPIR-V (bad magic)".into());
        }
        let mut m = Module::default();
        let mut i = 5;
        while i < words.len() {
            let count = (words[i] >> 16) as usize;
            let op = words[i] & 0xffff;
            if count == 0 || i + count > words.len() {
                return Err(format!("truncated instruction at word {i}"));
            }
            let a = &words[i + 1..i + count];
            match op {
                // OpExecutionMode %entry LocalSize x y z
                16 if a.get(1) == Some(&17) && a.len() >= 5 => m.local_size = Some([a[2], a[3], a[4]]),
                // OpExecutionModeId %entry LocalSizeId %x %y %z
                331 if a.get(1) == Some(&38) && a.len() >= 5 => m.local_size_ids = Some([a[2], a[3], a[4]]),
                // OpName, OpMemberName
                5 => {
                    m.names.insert(a[0], string(&a[1..]));
                }
                6 => {
                    m.member_names.insert((a[0], a[1]), string(&a[2..]));
                }
                21 => {
                    m.types.insert(a[0], Ty::Int(a[1] / 8, a[2] == 1));
                }
                22 => {
                    m.types.insert(a[0], Ty::Float(a[1] / 8));
                }
                23 => {
                    m.types.insert(a[0], Ty::Vector(a[1], a[2]));
                }
                24 => {
                    m.types.insert(a[0], Ty::Matrix(a[1], a[2]));
                }
                25 => {
                    m.types.insert(
                        a[0],
                        Ty::Image {
                            dim: a[2],
                            sampled: a[6],
                        },
                    );
                }
                26 => {
                    m.types.insert(a[0], Ty::Other);
                }
                27 => {
                    m.types.insert(a[0], Ty::SampledImage(a[1]));
                }
                28 => {
                    m.types.insert(a[0], Ty::Array(a[1], a[2]));
                }
                29 => {
                    m.types.insert(a[0], Ty::RuntimeArray(a[1]));
                }
                30 => {
                    m.types.insert(a[0], Ty::Struct(a[1..].to_vec()));
                }
                32 => {
                    m.types.insert(a[0], Ty::Pointer(a[2]));
                }
                // OpConstant, OpSpecConstant: %type %id value
                43 | 50 => {
                    m.constants.insert(a[1], a[2]);
                }
                // OpConstantComposite, OpSpecConstantComposite
                44 | 51 => {
                    m.composites.insert(a[1], a[2..].to_vec());
                }
                59 => m.variables.push((a[0], a[1], a[2])),
                71 => {
                    if a[1] == DEC_SPEC_ID {
                        m.spec_ids.insert(a[0], a[2]);
                    } else if a[1] == DEC_ARRAY_STRIDE {
                        m.array_strides.insert(a[0], a[2]);
                    }
                    m.decorations.insert((a[0], a[1]), a[2..].to_vec());
                }
                72 if a[2] == DEC_OFFSET => {
                    m.member_offsets.insert((a[0], a[1]), a[3]);
                }
                72 if a[2] == DEC_NON_WRITABLE => {
                    m.nonwritable_members.insert((a[0], a[1]));
                }
                _ => {}
            }
            i += count;
        }
        Ok(m)
    }

    /// Whether the storage block variable `id` of type `block` is declared
    /// `readonly`: the variable, or every member of its block, NonWritable.
    fn read_only(&self, id: u32, block: u32) -> bool {
        if self.decorations.contains_key(&(id, DEC_NON_WRITABLE)) {
            return true;
        }
        match self.types.get(&block) {
            Some(Ty::Struct(members)) => {
                !members.is_empty() && (0..members.len() as u32).all(|k| self.nonwritable_members.contains(&(block, k)))
            }
            _ => false,
        }
    }

    fn decoration(&self, id: u32, dec: u32) -> Option<u32> {
        self.decorations.get(&(id, dec)).and_then(|v| v.first().copied())
    }

    fn size_of(&self, ty: u32) -> Result<u32, String> {
        match self.types.get(&ty) {
            Some(Ty::Int(b, _) | Ty::Float(b)) => Ok(*b),
            Some(Ty::Vector(c, n)) => Ok(self.size_of(*c)? * n),
            Some(Ty::Matrix(col, n)) => Ok(self.size_of(*col)? * n),
            Some(Ty::Array(e, len)) => {
                let n = self.constants.get(len).ok_or("array length is not a constant")?;
                let stride = match self.array_strides.get(&ty) {
                    Some(s) => *s,
                    None => self.size_of(*e)?,
                };
                Ok(stride * n)
            }
            Some(Ty::Struct(members)) => {
                let mut end = 0;
                for (k, &mt) in members.iter().enumerate() {
                    let off = self.member_offsets.get(&(ty, k as u32)).copied().unwrap_or(0);
                    end = end.max(off + self.size_of(mt)?);
                }
                Ok(end)
            }
            other => Err(format!("no size for type {other:?}")),
        }
    }

    /// The offset of a struct's trailing runtime array (the fixed part's size).
    fn fixed_part(&self, ty: u32) -> Result<u32, String> {
        match self.types.get(&ty) {
            Some(Ty::Struct(members)) => {
                let k = members.len().checked_sub(1).ok_or("empty struct")?;
                match self.types.get(&members[k]) {
                    Some(Ty::RuntimeArray(_)) => Ok(self.member_offsets.get(&(ty, k as u32)).copied().unwrap_or(0)),
                    other => Err(format!("no size for type {other:?}")),
                }
            }
            other => Err(format!("no size for type {other:?}")),
        }
    }

    /// The Rust type with the layout of `ty` (std430/std140 members: arrays
    /// only where their stride is their element's size).
    fn rust_type(&self, ty: u32) -> Result<String, String> {
        match self.types.get(&ty) {
            Some(Ty::Int(4, true)) => Ok("i32".into()),
            Some(Ty::Int(4, false)) => Ok("u32".into()),
            Some(Ty::Float(4)) => Ok("f32".into()),
            Some(Ty::Vector(c, n)) => Ok(format!("[{}; {n}]", self.rust_type(*c)?)),
            Some(Ty::Matrix(col, n)) => Ok(format!("[{}; {n}]", self.rust_type(*col)?)),
            Some(Ty::Array(e, len)) => {
                let n = self.constants.get(len).ok_or("array length is not a constant")?;
                let stride = self.array_strides.get(&ty).copied().unwrap_or(0);
                if stride != 0 && stride != self.size_of(*e)? {
                    return Err(format!(
                        "an array of stride {stride} over elements of {} bytes has no Rust layout; use vec4 elements",
                        self.size_of(*e)?
                    ));
                }
                Ok(format!("[{}; {n}]", self.rust_type(*e)?))
            }
            Some(Ty::Struct(_)) => self.names.get(&ty).cloned().ok_or("a struct without a name".into()),
            other => Err(format!("no Rust type for {other:?}")),
        }
    }

    /// The fixed members of struct `ty` (a trailing runtime array left out),
    /// with the structs they contain appended to `out`.
    fn struct_def(&self, ty: u32, out: &mut Vec<Struct>) -> Result<Struct, String> {
        let Some(Ty::Struct(members)) = self.types.get(&ty) else {
            return Err(format!("type %{ty} is not a struct"));
        };
        let name = self.names.get(&ty).cloned().unwrap_or_default();
        let mut def = Struct {
            name: name.clone(),
            members: Vec::new(),
            size: 0,
        };
        for (k, &mt) in members.iter().enumerate() {
            let mut inner = mt;
            if matches!(self.types.get(&mt), Some(Ty::RuntimeArray(_))) {
                break;
            }
            while let Some(Ty::Array(e, _)) = self.types.get(&inner) {
                inner = *e;
            }
            if matches!(self.types.get(&inner), Some(Ty::Struct(_))) {
                let nested = self.struct_def(inner, out)?;
                if !out.contains(&nested) {
                    out.push(nested);
                }
            }
            let offset = self.member_offsets.get(&(ty, k as u32)).copied().unwrap_or(0);
            let size = self.size_of(mt)?;
            let member = self
                .member_names
                .get(&(ty, k as u32))
                .cloned()
                .filter(|n| !n.is_empty())
                .ok_or_else(|| format!("member {k} of struct {name} has no name"))?;
            def.members.push(Member {
                name: member,
                offset,
                rust: self.rust_type(mt).map_err(|e| format!("{name}.{k}: {e}"))?,
                size,
            });
            def.size = def.size.max(offset + size);
        }
        Ok(def)
    }

    /// The element struct of a block's trailing runtime array, if it is one.
    fn runtime_element(&self, ty: u32) -> Option<u32> {
        let Some(Ty::Struct(members)) = self.types.get(&ty) else {
            return None;
        };
        match self.types.get(members.last()?) {
            Some(Ty::RuntimeArray(e)) if matches!(self.types.get(e), Some(Ty::Struct(_))) => Some(*e),
            _ => None,
        }
    }

    fn dim(&self, id: u32) -> Result<Dim, String> {
        let value = *self.constants.get(&id).ok_or("workgroup size is not a constant")?;
        Ok(match self.spec_ids.get(&id) {
            Some(&sid) => Dim::Spec {
                id: sid,
                default: value,
            },
            None => Dim::Fixed(value),
        })
    }
}

pub fn reflect(words: &[u32]) -> Result<Interface, String> {
    let m = Module::parse(words)?;
    let mut slots: Vec<(u32, Slot)> = Vec::new();
    let mut push_size = 0;
    let mut push = None;
    let mut structs: Vec<Struct> = Vec::new();
    let add = |def: Struct, structs: &mut Vec<Struct>| {
        if !def.name.is_empty() && !structs.contains(&def) {
            structs.push(def);
        }
    };
    for &(ptr, id, class) in &m.variables {
        let Some(Ty::Pointer(pointee)) = m.types.get(&ptr) else {
            continue;
        };
        let pointee = *pointee;
        if class == SC_PUSH_CONSTANT {
            push_size = m.size_of(pointee)?;
            let mut nested = Vec::new();
            push = Some(m.struct_def(pointee, &mut nested)?);
            for n in nested {
                add(n, &mut structs);
            }
            continue;
        }
        let ty = match (class, m.types.get(&pointee)) {
            (SC_STORAGE_BUFFER, _) => Descriptor::StorageBuffer,
            (SC_UNIFORM, _) if m.decorations.contains_key(&(pointee, DEC_BUFFER_BLOCK)) => Descriptor::StorageBuffer,
            (SC_UNIFORM, _) if m.decorations.contains_key(&(pointee, DEC_BLOCK)) => Descriptor::UniformBuffer,
            (SC_UNIFORM_CONSTANT, Some(Ty::SampledImage(image))) => match m.types.get(image) {
                Some(Ty::Image { dim: DIM_BUFFER, .. }) => Descriptor::UniformTexelBuffer,
                _ => Descriptor::CombinedImageSampler,
            },
            (
                SC_UNIFORM_CONSTANT,
                Some(Ty::Image {
                    dim: DIM_BUFFER,
                    sampled: 2,
                }),
            ) => return Err(format!("resource %{id}: storage texel buffers are not used")),
            (SC_UNIFORM_CONSTANT, Some(Ty::Image { dim: DIM_BUFFER, .. })) => Descriptor::UniformTexelBuffer,
            (SC_UNIFORM_CONSTANT, Some(Ty::Image { sampled: 2, .. })) => Descriptor::StorageImage,
            (SC_UNIFORM_CONSTANT, Some(Ty::Image { .. })) => Descriptor::SampledImage,
            (SC_UNIFORM_CONSTANT | SC_UNIFORM, t) => {
                return Err(format!(
                    "resource %{id} of unsupported type {t:?} (arrays of descriptors are not used)"
                ))
            }
            _ => continue,
        };
        let set = m.decoration(id, DEC_SET).unwrap_or(0);
        if set != 0 {
            return Err(format!(
                "resource %{id} is in set {set}; lacuna's kernels use set 0 only"
            ));
        }
        let binding = m
            .decoration(id, DEC_BINDING)
            .ok_or(format!("resource %{id} has no binding"))?;
        // Storage blocks ending in a runtime array: the size of the part
        // before it (0 for a bare array).
        let size = match ty {
            Descriptor::UniformBuffer => m.size_of(pointee)?,
            Descriptor::StorageBuffer => m.size_of(pointee).or_else(|_| m.fixed_part(pointee)).unwrap_or(0),
            _ => 0,
        };
        if matches!(ty, Descriptor::UniformBuffer | Descriptor::StorageBuffer) {
            let mut nested = Vec::new();
            let block = m.struct_def(pointee, &mut nested)?;
            if let Some(e) = m.runtime_element(pointee) {
                let element = m.struct_def(e, &mut nested)?;
                nested.push(element);
            }
            for n in nested {
                add(n, &mut structs);
            }
            if !block.members.is_empty() {
                add(block, &mut structs);
            }
        }
        let name = match m.names.get(&id).filter(|n| !n.is_empty()) {
            Some(n) => n.clone(),
            None => snake_case(m.names.get(&pointee).ok_or(format!("resource %{id} has no name"))?),
        };
        let writes = match ty {
            Descriptor::StorageBuffer => !m.read_only(id, pointee),
            Descriptor::StorageImage => true,
            _ => false,
        };
        slots.push((
            binding,
            Slot {
                name,
                ty,
                block_size: size,
                writes,
            },
        ));
    }
    slots.sort_by_key(|s| s.0);
    for (k, (b, _)) in slots.iter().enumerate() {
        if *b != k as u32 {
            return Err(format!(
                "bindings of set 0 must be 0..{} without gaps (found binding {b} at position {k})",
                slots.len()
            ));
        }
    }
    // A WorkgroupSize built-in (local_size_*_id) overrides the execution mode.
    let builtin = m
        .decorations
        .iter()
        .find(|((_, dec), v)| *dec == DEC_BUILTIN && v.first() == Some(&BUILTIN_WORKGROUP_SIZE))
        .map(|((id, _), _)| *id);
    let local_size = if let Some(c) = builtin {
        let parts = m
            .composites
            .get(&c)
            .ok_or("WorkgroupSize is not a composite constant")?;
        [m.dim(parts[0])?, m.dim(parts[1])?, m.dim(parts[2])?]
    } else if let Some(ids) = m.local_size_ids {
        [m.dim(ids[0])?, m.dim(ids[1])?, m.dim(ids[2])?]
    } else if let Some(l) = m.local_size {
        l.map(Dim::Fixed)
    } else {
        return Err("no workgroup size".into());
    };
    let mut names: Vec<&str> = slots.iter().map(|s| s.1.name.as_str()).collect();
    names.sort_unstable();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        return Err(format!("two bindings are named {}", w[0]));
    }
    Ok(Interface {
        bindings: slots.into_iter().map(|s| s.1).collect(),
        push_size,
        push,
        structs,
        local_size,
    })
}

/// A SPIR-V literal string: UTF-8, nul-terminated, packed little-endian.
fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .take_while(|&b| b != 0)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// `CellFlags` -> `cell_flags`.
pub fn snake_case(name: &str) -> String {
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}
