//! Resolving a validated graph for one frame configuration: expression values (sizes, mips,
//! sample counts, settings, dispatch) and the range each must lie in.
//!
//! The range checks are shared with validation, which applies them as soon as an expression
//! uses params only, so `cullgraph graph check` reports them without a scene.

use super::FrameInputs;
use crate::graph::error::Pos;
use crate::graph::expr::Num;
use crate::graph::kinds::{SettingDefault, SettingOverride};
use crate::graph::plan::SettingValue;
use crate::graph::validate::kind_variables;
use crate::graph::validated::{
    DispatchSpec, ImageSize, LocatedExpr, Mips, Param, ParamValue, Pass, ResourceDesc, SettingSource, ValidatedGraph,
};
use ash::vk;
use std::collections::{BTreeMap, HashMap};

/// Largest buffer, in bytes.
pub const MAX_BUFFER_BYTES: u64 = 1 << 40;
/// Largest image width or height.
pub const MAX_IMAGE_DIMENSION: u32 = 16384;
/// Buffers sized 0 (e.g. `lights * 32` without lights) get this many bytes.
pub const MIN_BUFFER_BYTES: u64 = 4;
/// Most workgroups per dimension of a dispatch (the Vulkan minimum of `maxComputeWorkGroupCount`).
pub const MAX_GROUPS: u64 = 65535;
/// Most workgroups of one dispatch in all. Vulkan bounds each dimension only, so 65535^3
/// workgroups are a valid dispatch that keeps a device busy for hours (lavapipe never returns,
/// a GPU is reset by its watchdog). 2^22 is one 8x8 workgroup per 8x8 tile of the largest image
/// (16384x16384), and a trivial shader runs that many in about a second on lavapipe with two
/// cores (8x8 threads a workgroup; 8 s at the most threads a workgroup that lavapipe allows,
/// 32x32); more work belongs in more threads per workgroup or in several passes.
pub const MAX_DISPATCH_GROUPS: u64 = 1 << 22;

/// Which resources exist in this frame: those without `when`, and those whose `when` is not 0
/// (one that cannot be evaluated is reported and counts as present).
pub fn present(graph: &ValidatedGraph, vars: &BTreeMap<String, Num>, errors: &mut Errors<'_>) -> Vec<bool> {
    let nonzero =
        |n: Num| if n.as_f64().is_finite() { Ok(n.as_f64() != 0.0) } else { Err(format!("is not finite ({n})")) };
    graph
        .resources
        .iter()
        .map(|r| match &r.when {
            Some(when) => {
                errors.value(when, vars, &format!("condition of resource '{}'", r.name), nonzero).unwrap_or(true)
            }
            None => true,
        })
        .collect()
}

/// Evaluates `e`; an error carries its position.
pub fn eval(e: &LocatedExpr, vars: &BTreeMap<String, Num>) -> Result<Num, (Pos, String)> {
    e.expr.eval(vars).map_err(|err| (e.pos_at(err.offset), err.message))
}

fn whole(n: Num) -> Result<i64, String> {
    match n {
        Num::Float(f) if !f.is_finite() => Err(format!("is not finite ({f})")),
        _ => n.as_whole().ok_or_else(|| format!("is not a whole number ({n})")),
    }
}

/// Bytes of a buffer: whole, not negative, at most 2^40; 0 becomes [`MIN_BUFFER_BYTES`].
pub fn buffer_bytes(n: Num) -> Result<u64, String> {
    let v = whole(n)?;
    if v < 0 {
        return Err(format!("is negative ({v})"));
    }
    if v as u64 > MAX_BUFFER_BYTES {
        return Err(format!("is {v} bytes, more than 2^40"));
    }
    Ok((v as u64).max(MIN_BUFFER_BYTES))
}

/// An image width or height: whole, 1 to 16384.
pub fn image_dimension(n: Num) -> Result<u32, String> {
    let v = whole(n)?;
    if !(1..=MAX_IMAGE_DIMENSION as i64).contains(&v) {
        return Err(format!("is {v} (must be 1 to {MAX_IMAGE_DIMENSION})"));
    }
    Ok(v as u32)
}

/// A `Scaled(..)` factor: finite and positive.
pub fn scale(n: Num) -> Result<f64, String> {
    let f = n.as_f64();
    if !f.is_finite() || f <= 0.0 {
        return Err(format!("must be a positive number, got {n}"));
    }
    Ok(f)
}

/// A mip count for a `width` x `height` image: whole, 1 to the full chain.
pub fn mip_count(n: Num, width: u32, height: u32) -> Result<u32, String> {
    let v = whole(n)?;
    let full = full_mip_chain(width, height);
    if v < 1 || v > full as i64 {
        return Err(format!("is {v} (a {width}x{height} image has 1 to {full} levels)"));
    }
    Ok(v as u32)
}

/// Levels of a full mip chain down to 1x1.
pub fn full_mip_chain(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

/// A sample count: 1, 2, 4 or 8.
pub fn sample_count(n: Num) -> Result<u32, String> {
    match n.as_whole() {
        Some(v @ (1 | 2 | 4 | 8)) => Ok(v as u32),
        _ => Err(format!("must be 1, 2, 4 or 8, got {n}")),
    }
}

/// `vk::SampleCountFlags` of a count of 1, 2, 4 or 8.
pub fn sample_flags(count: u32) -> vk::SampleCountFlags {
    vk::SampleCountFlags::from_raw(count.max(1))
}

/// Variables of expressions for one frame: numeric params, the output size and the registered
/// `quantities` (0 where the host gave no value).
pub fn variables(params: &[Param], frame: &FrameInputs, quantities: &[&str]) -> BTreeMap<String, Num> {
    let mut vars: BTreeMap<String, Num> =
        params.iter().filter_map(|p| Some((p.name.clone(), p.value.as_num()?))).collect();
    vars.extend(frame_variables(frame, quantities));
    vars
}

/// The output size and the registered `quantities` of one frame, as variables.
pub fn frame_variables(frame: &FrameInputs, quantities: &[&str]) -> BTreeMap<String, Num> {
    let q = |v: u64| Num::Int(v.min(i64::MAX as u64) as i64);
    let mut vars = BTreeMap::new();
    vars.insert("width".into(), Num::Int(frame.width as i64));
    vars.insert("height".into(), Num::Int(frame.height as i64));
    for name in quantities {
        vars.insert(name.to_string(), q(frame.quantity(name)));
    }
    vars
}

/// A resource resolved for one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resolved {
    /// An image.
    Image {
        /// Format.
        format: vk::Format,
        /// Mip-0 size.
        extent: vk::Extent2D,
        /// Levels.
        mips: u32,
        /// Samples.
        samples: u32,
    },
    /// A buffer of this many bytes.
    Buffer(u64),
}

/// Collects errors while resolving.
pub struct Errors<'a> {
    /// The graph's files, for messages.
    pub files: &'a [String],
    /// Found so far.
    pub list: Vec<crate::graph::error::GraphError>,
}

impl Errors<'_> {
    fn push(&mut self, pos: Pos, message: String) {
        let file = crate::graph::error::file_of(self.files, pos);
        self.list.push(crate::graph::error::GraphError::new(file, pos, message));
    }

    /// Evaluates `e` and checks it with `check`; errors are recorded with `what` in front.
    fn value<T>(
        &mut self,
        e: &LocatedExpr,
        vars: &BTreeMap<String, Num>,
        what: &str,
        check: impl Fn(Num) -> Result<T, String>,
    ) -> Option<T> {
        match eval(e, vars) {
            Ok(n) => match check(n) {
                Ok(v) => Some(v),
                Err(m) => {
                    self.push(e.pos, format!("{what} {m}"));
                    None
                }
            },
            Err((pos, m)) => {
                self.push(pos, format!("{what}: {m}"));
                None
            }
        }
    }
}

/// Resolves every resource of `graph`: declared ones with `vars` (params, output size and
/// quantities), ones a kind created with `frame_vars` (output size and quantities) and their
/// pass's `settings`, and images sized like another resource after that one.
pub fn resources(
    graph: &ValidatedGraph,
    vars: &BTreeMap<String, Num>,
    frame_vars: &BTreeMap<String, Num>,
    settings: &[BTreeMap<String, SettingValue>],
    frame: &FrameInputs,
    errors: &mut Errors<'_>,
) -> Vec<Resolved> {
    let mut resolved: Vec<Option<Resolved>> = vec![None; graph.resources.len()];
    // Each round resolves what depends on nothing unresolved; a resource sized like itself
    // through others is never resolved, and is reported.
    loop {
        let mut progress = false;
        for (r, res) in graph.resources.iter().enumerate() {
            if resolved[r].is_some() {
                continue;
            }
            if let ResourceDesc::Image { size: ImageSize::Like { resource, .. }, .. } = res.desc {
                if resolved.get(resource).is_none_or(Option::is_none) {
                    continue;
                }
            }
            let owner_vars;
            let vars = match &res.owner {
                Some(owner) => {
                    owner_vars = kind_variables(frame_vars, &settings[owner.pass]);
                    &owner_vars
                }
                None => vars,
            };
            resolved[r] = Some(resource(&res.describe(), &res.desc, vars, frame, &resolved, errors));
            progress = true;
        }
        if !progress {
            break;
        }
    }
    resolved
        .into_iter()
        .enumerate()
        .map(|(r, res)| {
            res.unwrap_or_else(|| {
                let res = &graph.resources[r];
                errors.push(res.pos, format!("the size of {} depends on itself", res.describe()));
                Resolved::Buffer(MIN_BUFFER_BYTES)
            })
        })
        .collect()
}

/// Resolves one resource description (`name` as messages say it); `resolved` holds the
/// resources resolved so far.
fn resource(
    name: &str,
    desc: &ResourceDesc,
    vars: &BTreeMap<String, Num>,
    frame: &FrameInputs,
    resolved: &[Option<Resolved>],
    errors: &mut Errors<'_>,
) -> Resolved {
    match desc {
        ResourceDesc::Buffer { size } => {
            Resolved::Buffer(errors.value(size, vars, &format!("size of buffer {name}"), buffer_bytes).unwrap_or(4))
        }
        ResourceDesc::Image { format, size, mips, samples, .. } => {
            let (w, h) = match size {
                ImageSize::Like { resource, divisor } => match resolved.get(*resource) {
                    Some(Some(Resolved::Image { extent, .. })) => {
                        ((extent.width / divisor).max(1), (extent.height / divisor).max(1))
                    }
                    _ => (1, 1),
                },
                ImageSize::Output => (frame.width.max(1), frame.height.max(1)),
                ImageSize::Scaled(f) => {
                    let f = errors.value(f, vars, &format!("scale of image {name}"), scale).unwrap_or(1.0);
                    let dim = |v: u32| ((v as f64 * f).ceil() as u64).clamp(1, MAX_IMAGE_DIMENSION as u64) as u32;
                    (dim(frame.width), dim(frame.height))
                }
                ImageSize::Fixed(w, h) => (
                    errors.value(w, vars, &format!("width of image {name}"), image_dimension).unwrap_or(1),
                    errors.value(h, vars, &format!("height of image {name}"), image_dimension).unwrap_or(1),
                ),
            };
            let mips = match mips {
                Mips::All => full_mip_chain(w, h),
                Mips::Count(e) => {
                    errors.value(e, vars, &format!("mips of image {name}"), |n| mip_count(n, w, h)).unwrap_or(1)
                }
            };
            let samples = errors.value(samples, vars, &format!("samples of image {name}"), sample_count).unwrap_or(1);
            Resolved::Image { format: *format, extent: vk::Extent2D { width: w, height: h }, mips, samples }
        }
    }
}

/// Settings of a pass with defaults filled in.
pub fn settings(
    pass: &Pass,
    declared: &[crate::graph::kinds::SettingDecl],
    params: &HashMap<&str, &ParamValue>,
    vars: &BTreeMap<String, Num>,
    errors: &mut Errors<'_>,
) -> BTreeMap<String, SettingValue> {
    let mut out: BTreeMap<String, SettingValue> =
        declared.iter().map(|decl| (decl.name.to_string(), decl.default.value())).collect();
    for s in &pass.settings {
        let what = format!("setting '{}' of pass '{}'", s.name, pass.name);
        let value = match &s.source {
            SettingSource::Value(v) => Some(v.clone()),
            SettingSource::Param(p) => match (params.get(p.as_str()), &s.ty) {
                (Some(ParamValue::Bool(b)), SettingDefault::Bool(_)) => Some(SettingValue::Bool(*b)),
                (Some(ParamValue::Str(v)), SettingDefault::Choice(options)) => {
                    if options.contains(&v.as_str()) {
                        Some(SettingValue::Choice(v.clone()))
                    } else {
                        errors
                            .push(s.pos, format!("{what}: param '{p}' is \"{v}\", not one of {}", options.join(", ")));
                        None
                    }
                }
                _ => None,
            },
            SettingSource::Expr(e) => match s.ty {
                SettingDefault::Int(_) => errors.value(e, vars, &what, whole).map(SettingValue::Int),
                _ => errors
                    .value(e, vars, &what, |n| {
                        let f = n.as_f64();
                        if f.is_finite() {
                            Ok(f)
                        } else {
                            Err(format!("is not finite ({f})"))
                        }
                    })
                    .map(SettingValue::Float),
            },
        };
        if let Some(v) = value {
            // Literal values were checked at load time; what params and expressions give, here.
            let literal = matches!(s.source, SettingSource::Value(_));
            let decl = declared.iter().find(|d| d.name == s.name);
            if let Some(why) = decl.filter(|_| !literal).and_then(|d| d.range_error(&v)) {
                errors.push(s.pos, format!("{what} {why}"));
            }
            out.insert(s.name.clone(), v);
        }
    }
    out
}

/// Applies `overrides` to the resolved `settings` of the passes they name. An unknown pass or
/// setting, or a value that is not of the setting's type or outside its range, is an error of
/// the command line (the overrides come from the host, not the file).
pub(crate) fn setting_overrides(
    graph: &ValidatedGraph,
    overrides: &[SettingOverride],
    settings: &mut [BTreeMap<String, SettingValue>],
    sink: &mut crate::graph::error::Sink,
) {
    for o in overrides {
        let what = format!("setting {}.{}={}", o.pass, o.setting, o.value);
        let Some(p) = graph.pass_index(&o.pass) else {
            sink.command_line(format!("{what}: no pass '{}'", o.pass));
            continue;
        };
        let Some(decl) = graph.kind(p).and_then(|k| k.settings.iter().find(|s| s.name == o.setting)) else {
            sink.command_line(format!("{what}: pass '{}' has no setting '{}'", o.pass, o.setting));
            continue;
        };
        let text = o.value.trim();
        let value = match &decl.default {
            SettingDefault::Bool(_) => text.parse().ok().map(SettingValue::Bool),
            SettingDefault::Int(_) => text.parse().ok().map(SettingValue::Int),
            SettingDefault::Float(_) => text.parse::<f64>().ok().filter(|f| f.is_finite()).map(SettingValue::Float),
            SettingDefault::Choice(words) => words.contains(&text).then(|| SettingValue::Choice(text.to_string())),
        };
        match value {
            None => sink.command_line(format!("{what}: not a value of the setting's type")),
            Some(v) => match decl.range_error(&v) {
                Some(why) => sink.command_line(format!("{what}: {why}")),
                None => {
                    settings[p].insert(o.setting.clone(), v);
                }
            },
        }
    }
}

/// Workgroup counts of a compute pass.
pub fn dispatch(
    pass: &Pass,
    resolved: &[Resolved],
    resource_names: &[String],
    vars: &BTreeMap<String, Num>,
    errors: &mut Errors<'_>,
) -> Option<[u32; 3]> {
    let spec = pass.dispatch.as_ref()?;
    let ls = pass.local_size.map(|v| v.max(1) as u64);
    let axes = ["x", "y", "z"];
    let threads_to_groups = |t: [u64; 3]| [0, 1, 2].map(|i| t[i].div_ceil(ls[i]));
    let groups: [u64; 3] = match spec {
        DispatchSpec::PerPixel(r) => match resolved.get(*r) {
            Some(Resolved::Image { extent, .. }) => threads_to_groups([extent.width as u64, extent.height as u64, 1]),
            _ => {
                let name = resource_names.get(*r).map_or("?", |s| s.as_str());
                errors.push(pass.dispatch_pos, format!("dispatch of pass '{}': '{name}' is not an image", pass.name));
                return None;
            }
        },
        DispatchSpec::Threads(e) | DispatchSpec::Groups(e) => {
            let mut v = [0u64; 3];
            for i in 0..3 {
                let what = format!("dispatch {} of pass '{}'", axes[i], pass.name);
                v[i] = errors.value(&e[i], vars, &what, |n| {
                    let w = whole(n)?;
                    u64::try_from(w).map_err(|_| format!("is negative ({w})"))
                })?;
            }
            if matches!(spec, DispatchSpec::Threads(_)) {
                threads_to_groups(v)
            } else {
                v
            }
        }
    };
    for i in 0..3 {
        if groups[i] > MAX_GROUPS {
            errors.push(
                pass.dispatch_pos,
                format!(
                    "dispatch of pass '{}' needs {} workgroups in {} (at most {MAX_GROUPS})",
                    pass.name, groups[i], axes[i]
                ),
            );
            return None;
        }
    }
    let total = groups[0] * groups[1] * groups[2];
    if total > MAX_DISPATCH_GROUPS {
        errors.push(
            pass.dispatch_pos,
            format!(
                "dispatch of pass '{}' needs {}x{}x{} = {total} workgroups (at most {MAX_DISPATCH_GROUPS} in all)",
                pass.name, groups[0], groups[1], groups[2]
            ),
        );
        return None;
    }
    Some(groups.map(|g| g as u32))
}
