//! Reads a compute shader's interface from its SPIR-V words: descriptor
//! bindings of set 0 with their types, the push-constant block's size and the
//! workgroup size (literal or specialization constants). Only the few
//! instructions that carry these are decoded.

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

pub struct Interface {
    /// Bindings 0.. of set 0, in order.
    pub bindings: Vec<Descriptor>,
    /// Per binding: the block size in bytes of a uniform or storage buffer
    /// (of a storage block ending in a runtime array, the part before it),
    /// else 0.
    pub block_sizes: Vec<u32>,
    pub push_size: u32,
    pub local_size: [Dim; 3],
}

#[derive(Clone, Debug)]
enum Ty {
    Scalar(u32),
    Vector(u32, u32),
    Matrix(u32, u32),
    Array(u32, u32),
    RuntimeArray,
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
    array_strides: HashMap<u32, u32>,
    variables: Vec<(u32, u32, u32)>,
    local_size: Option<[u32; 3]>,
    local_size_ids: Option<[u32; 3]>,
}

const DEC_SPEC_ID: u32 = 1;
const DEC_BLOCK: u32 = 2;
const DEC_BUFFER_BLOCK: u32 = 3;
const DEC_ARRAY_STRIDE: u32 = 6;
const DEC_BUILTIN: u32 = 11;
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
                21 | 22 => {
                    m.types.insert(a[0], Ty::Scalar(a[1] / 8));
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
                    m.types.insert(a[0], Ty::RuntimeArray);
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
                _ => {}
            }
            i += count;
        }
        Ok(m)
    }

    fn decoration(&self, id: u32, dec: u32) -> Option<u32> {
        self.decorations.get(&(id, dec)).and_then(|v| v.first().copied())
    }

    fn size_of(&self, ty: u32) -> Result<u32, String> {
        match self.types.get(&ty) {
            Some(Ty::Scalar(b)) => Ok(*b),
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
                    Some(Ty::RuntimeArray) => Ok(self.member_offsets.get(&(ty, k as u32)).copied().unwrap_or(0)),
                    other => Err(format!("no size for type {other:?}")),
                }
            }
            other => Err(format!("no size for type {other:?}")),
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
    let mut slots: Vec<(u32, Descriptor, u32)> = Vec::new();
    let mut push_size = 0;
    for &(ptr, id, class) in &m.variables {
        let Some(Ty::Pointer(pointee)) = m.types.get(&ptr) else {
            continue;
        };
        let pointee = *pointee;
        if class == SC_PUSH_CONSTANT {
            push_size = m.size_of(pointee)?;
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
        slots.push((binding, ty, size));
    }
    slots.sort_by_key(|s| s.0);
    for (k, (b, _, _)) in slots.iter().enumerate() {
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
    Ok(Interface {
        bindings: slots.iter().map(|s| s.1).collect(),
        block_sizes: slots.iter().map(|s| s.2).collect(),
        push_size,
        local_size,
    })
}
