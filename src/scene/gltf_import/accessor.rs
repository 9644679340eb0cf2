//! Bounds-checked reads of glTF accessors (positions, normals, indices), sparse included.
//!
//! The `gltf` crate's own readers assume a well-formed file (they `debug_assert!` element sizes
//! and subtract from a zero count); these checks turn every such case into an error message that
//! names the accessor, the buffer view and the byte range instead.

use gltf::accessor::{sparse::IndexType, DataType, Dimensions};
use gltf::Accessor;

/// Upper bound on the element count of an accessor that has no buffer view (all zeros plus
/// sparse substitutions), so that a hostile `count` cannot trigger a huge allocation.
const MAX_VIEWLESS_ELEMENTS: usize = 1 << 26;

/// Reads a `VEC3` of `FLOAT` accessor.
pub(super) fn read_vec3(accessor: &Accessor<'_>, buffers: &[Vec<u8>]) -> Result<Vec<[f32; 3]>, String> {
    expect_type(accessor, Dimensions::Vec3, &[DataType::F32], "VEC3 of FLOAT")?;
    read(accessor, buffers, 12, |b| [f32_at(b, 0), f32_at(b, 4), f32_at(b, 8)])
}

/// Reads texture coordinates: a `VEC2` of `FLOAT`, or of normalized `UNSIGNED_BYTE` or
/// `UNSIGNED_SHORT`.
pub(super) fn read_uv(accessor: &Accessor<'_>, buffers: &[Vec<u8>]) -> Result<Vec<[f32; 2]>, String> {
    let what = "VEC2 of FLOAT, or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT";
    expect_type(accessor, Dimensions::Vec2, &[DataType::F32, DataType::U8, DataType::U16], what)?;
    match accessor.data_type() {
        DataType::F32 => read(accessor, buffers, 8, |b| [f32_at(b, 0), f32_at(b, 4)]),
        _ if !accessor.normalized() => Err(format!("must be {what}, found integers that are not normalized")),
        DataType::U8 => read(accessor, buffers, 2, |b| [b[0] as f32 / 255.0, b[1] as f32 / 255.0]),
        _ => read(accessor, buffers, 4, |b| {
            let u = |at: usize| u16::from_le_bytes([b[at], b[at + 1]]) as f32 / 65535.0;
            [u(0), u(2)]
        }),
    }
}

/// Reads a `VEC4` of `FLOAT` accessor (tangents).
pub(super) fn read_vec4(accessor: &Accessor<'_>, buffers: &[Vec<u8>]) -> Result<Vec<[f32; 4]>, String> {
    expect_type(accessor, Dimensions::Vec4, &[DataType::F32], "VEC4 of FLOAT")?;
    read(accessor, buffers, 16, |b| [f32_at(b, 0), f32_at(b, 4), f32_at(b, 8), f32_at(b, 12)])
}

/// Reads a `SCALAR` accessor of `UNSIGNED_BYTE`, `UNSIGNED_SHORT` or `UNSIGNED_INT` as indices.
pub(super) fn read_indices(accessor: &Accessor<'_>, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    expect_type(
        accessor,
        Dimensions::Scalar,
        &[DataType::U8, DataType::U16, DataType::U32],
        "SCALAR of an unsigned integer type",
    )?;
    match accessor.data_type() {
        DataType::U8 => read(accessor, buffers, 1, |b| b[0] as u32),
        DataType::U16 => read(accessor, buffers, 2, |b| u16::from_le_bytes([b[0], b[1]]) as u32),
        _ => read(accessor, buffers, 4, |b| u32_at(b, 0)),
    }
}

/// The element count of `accessor` as its document declares it, when its elements fit in its
/// buffer view and the view in its buffer's declared `byteLength` (or, without a view, within
/// [`MAX_VIEWLESS_ELEMENTS`]); `None` otherwise, for the read to report. Reads nothing, so the
/// scene's totals are known before any buffer is loaded.
pub(super) fn declared_count(accessor: &Accessor<'_>) -> Option<usize> {
    let count = accessor.count();
    let Some(view) = accessor.view() else {
        return (count <= MAX_VIEWLESS_ELEMENTS).then_some(count);
    };
    let size = accessor.size();
    let stride = view.stride().unwrap_or(size).max(size);
    let view_end = view.offset().checked_add(view.length())?;
    let elements_end = count.checked_sub(1)?.checked_mul(stride)?.checked_add(size)?.checked_add(accessor.offset())?;
    (view_end <= view.buffer().length() && elements_end <= view.length()).then_some(count)
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn expect_type(accessor: &Accessor<'_>, dims: Dimensions, types: &[DataType], what: &str) -> Result<(), String> {
    if accessor.dimensions() != dims || !types.contains(&accessor.data_type()) {
        return Err(format!(
            "must be {what}, found {:?} of {:?}{}",
            accessor.dimensions(),
            accessor.data_type(),
            if accessor.normalized() { " (normalized)" } else { "" }
        ));
    }
    Ok(())
}

/// Reads `accessor.count()` elements of `size` bytes each, decoding them with `decode`.
fn read<T: Copy + Default>(
    accessor: &Accessor<'_>,
    buffers: &[Vec<u8>],
    size: usize,
    decode: impl Fn(&[u8]) -> T,
) -> Result<Vec<T>, String> {
    let count = accessor.count();
    if count == 0 {
        return Err("has count 0".into());
    }
    let allocate = || {
        let mut out = Vec::new();
        out.try_reserve_exact(count).map_err(|_| format!("cannot allocate memory for its {count} elements"))?;
        Ok::<Vec<T>, String>(out)
    };
    let mut out = match accessor.view() {
        Some(view) => {
            let bytes = strided(&view, accessor.offset(), count, size, buffers)?;
            let stride = view.stride().unwrap_or(size);
            let mut out = allocate()?;
            out.extend((0..count).map(|i| decode(&bytes[i * stride..i * stride + size])));
            out
        }
        None if accessor.sparse().is_none() => return Err("has neither a buffer view nor sparse data".into()),
        None if count > MAX_VIEWLESS_ELEMENTS => {
            return Err(format!("has no buffer view and a count of {count} (at most {MAX_VIEWLESS_ELEMENTS})"))
        }
        None => {
            let mut out = allocate()?;
            out.resize(count, T::default());
            out
        }
    };
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 {
            return Err("sparse: count is 0".into());
        }
        let indices = sparse.indices();
        let index_size = match indices.index_type() {
            IndexType::U8 => 1,
            IndexType::U16 => 2,
            IndexType::U32 => 4,
        };
        let index_bytes = strided(&indices.view(), indices.offset(), n, index_size, buffers)
            .map_err(|e| format!("sparse indices: {e}"))?;
        let index_stride = indices.view().stride().unwrap_or(index_size);
        let values = sparse.values();
        let value_bytes =
            strided(&values.view(), values.offset(), n, size, buffers).map_err(|e| format!("sparse values: {e}"))?;
        let value_stride = values.view().stride().unwrap_or(size);
        for k in 0..n {
            let b = &index_bytes[k * index_stride..];
            let at = match index_size {
                1 => b[0] as usize,
                2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                _ => u32_at(b, 0) as usize,
            };
            let slot = out.get_mut(at).ok_or_else(|| {
                format!("sparse index {at} (entry {k}) is out of range (the accessor has {count} elements)")
            })?;
            *slot = decode(&value_bytes[k * value_stride..k * value_stride + size]);
        }
    }
    Ok(out)
}

/// The bytes of `count` elements of `size` bytes at `offset` in `view`, checked against the
/// view and the buffer. The slice starts at the first element and ends after the last one.
fn strided<'b>(
    view: &gltf::buffer::View<'_>,
    offset: usize,
    count: usize,
    size: usize,
    buffers: &'b [Vec<u8>],
) -> Result<&'b [u8], String> {
    let buffer = view.buffer().index();
    let data = buffers.get(buffer).ok_or_else(|| format!("buffer {buffer} was not loaded"))?;
    let view_start = view.offset();
    let view_end = view_start.checked_add(view.length()).filter(|&end| end <= data.len()).ok_or_else(|| {
        format!(
            "buffer view {} (bytes {view_start}..+{}) exceeds buffer {buffer}, which has {} bytes",
            view.index(),
            view.length(),
            data.len()
        )
    })?;
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "buffer view {} has byteStride {stride}, smaller than the element size {size}",
            view.index()
        ));
    }
    let needed = count
        .checked_sub(1)
        .and_then(|last| last.checked_mul(stride))
        .and_then(|b| b.checked_add(size))
        .and_then(|b| b.checked_add(offset))
        .filter(|&end| end <= view_end - view_start)
        .ok_or_else(|| {
            format!(
                "{count} elements of {size} bytes (stride {stride}) at offset {offset} do not fit in buffer view {}, which has {} bytes",
                view.index(),
                view.length()
            )
        })?;
    Ok(&data[view_start + offset..view_start + needed])
}

/// Components per element of `dims` (the element types animations and skins use).
fn components(dims: Dimensions) -> usize {
    match dims {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 | Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

/// Reads an accessor of `dims` elements as flat floats: `FLOAT`, or one of the `normalized`
/// integer types, mapped to [0, 1] or [-1, 1] as glTF specifies. `what` names the allowed types
/// in the error.
pub(super) fn read_floats(
    accessor: &Accessor<'_>,
    buffers: &[Vec<u8>],
    dims: Dimensions,
    normalized: &[DataType],
    what: &str,
) -> Result<Vec<f32>, String> {
    let types: Vec<DataType> = std::iter::once(DataType::F32).chain(normalized.iter().copied()).collect();
    expect_type(accessor, dims, &types, what)?;
    let c = components(dims);
    let ty = accessor.data_type();
    if ty != DataType::F32 && !accessor.normalized() {
        return Err(format!("must be {what}, found integers that are not normalized"));
    }
    let size = ty.size();
    let decode = move |b: &[u8]| -> f32 {
        match ty {
            DataType::I8 => (b[0] as i8 as f32 / 127.0).max(-1.0),
            DataType::U8 => b[0] as f32 / 255.0,
            DataType::I16 => (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
            DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
            _ => f32_at(b, 0),
        }
    };
    // Matrices of 1- and 2-byte components pad their columns to 4 bytes; no type used here has them.
    let elements = read(accessor, buffers, c * size, |b| {
        let mut e = [0.0f32; 16];
        for (i, v) in e.iter_mut().take(c).enumerate() {
            *v = decode(&b[i * size..]);
        }
        e
    })?;
    Ok(elements.iter().flat_map(|e| e[..c].iter().copied()).collect())
}

/// Reads skin joint indices: a `VEC4` of `UNSIGNED_BYTE` or `UNSIGNED_SHORT`.
pub(super) fn read_joints(accessor: &Accessor<'_>, buffers: &[Vec<u8>]) -> Result<Vec<[u16; 4]>, String> {
    expect_type(accessor, Dimensions::Vec4, &[DataType::U8, DataType::U16], "VEC4 of UNSIGNED_BYTE or UNSIGNED_SHORT")?;
    if accessor.normalized() {
        return Err("joint indices must not be normalized".into());
    }
    match accessor.data_type() {
        DataType::U8 => read(accessor, buffers, 4, |b| [b[0] as u16, b[1] as u16, b[2] as u16, b[3] as u16]),
        _ => read(accessor, buffers, 8, |b| std::array::from_fn(|i| u16::from_le_bytes([b[2 * i], b[2 * i + 1]]))),
    }
}
