//! Which graph the viewer runs: the one named on the command line and the shipped ones, G and
//! Shift+G stepping through them, with the culling-stat overlay composed over any of them.

use cullgraph::render::GraphSpec;
use cullgraph::Result;
use std::path::PathBuf;

/// The overlay's views, in the order V steps through them.
const OVERLAY_VIEWS: [&str; 3] = ["stats", "hiz", "culled"];

/// A graph to run.
#[derive(Clone, Debug, PartialEq)]
enum Entry {
    /// Shipped in `graph/`.
    Builtin(String),
    /// A file (reloaded when it changes).
    File(PathBuf),
}

/// What the keys chose.
#[derive(Clone, Copy, Debug, PartialEq)]
struct State {
    index: usize,
    overlay: bool,
    view: usize,
}

/// The graphs to step through and the choice of the moment.
pub struct GraphChoice {
    list: Vec<Entry>,
    now: State,
    /// The last state the renderer accepted, and the one before it (a graph that compiled
    /// can still fail its first frame, and then the one before comes back).
    good: State,
    before_good: State,
    /// The culling-stat overlay over the graph.
    pub overlay: bool,
    /// The MSAA sample count set through the graph's `msaa` param, if any (forgotten when
    /// another graph is chosen).
    pub msaa: Option<u32>,
    /// A graph was accepted and has not presented a frame yet.
    pub reloaded_untried: bool,
}

impl GraphChoice {
    /// The shipped graphs that draw a camera's frame (not the shadow maps' or the overlay,
    /// which O composes over any of them), with `arg` (`--graph`) first when it is a file.
    pub fn new(arg: Option<&str>) -> Result<Self> {
        let mut list: Vec<Entry> = cullgraph::passes::builtin_kinds()
            .graphs()
            .map(|g| g.name)
            .filter(|n| !n.starts_with("shadow") && *n != "overlay")
            .map(|n| Entry::Builtin(n.to_string()))
            .collect();
        let start = match arg {
            None => Entry::Builtin("default".into()),
            Some(arg) => match arg.strip_prefix("builtin:") {
                Some(name) => {
                    GraphSpec::builtin(name)?;
                    Entry::Builtin(name.to_string())
                }
                None => Entry::File(PathBuf::from(arg)),
            },
        };
        let index = match list.iter().position(|e| *e == start) {
            Some(i) => i,
            None => {
                list.insert(0, start);
                0
            }
        };
        let now = State { index, overlay: false, view: 0 };
        Ok(Self { list, now, good: now, before_good: now, overlay: false, msaa: None, reloaded_untried: false })
    }

    /// The graph file chosen now, if it is one (to watch for changes).
    pub fn file(&self) -> Option<&str> {
        match &self.list[self.now.index] {
            Entry::File(path) => path.to_str(),
            Entry::Builtin(_) => None,
        }
    }

    /// Steps `delta` graphs on (negative: back), round the list.
    pub fn step(&mut self, delta: isize) {
        let n = self.list.len() as isize;
        self.now.index = (self.now.index as isize + delta).rem_euclid(n) as usize;
        // A sample count belongs to the graph M set it on.
        self.msaa = None;
    }

    /// The overlay's next view.
    pub fn next_overlay_view(&mut self) {
        self.now.view = (self.now.view + 1) % OVERLAY_VIEWS.len();
    }

    /// The overlay's view now.
    pub fn overlay_view(&self) -> &'static str {
        OVERLAY_VIEWS[self.now.view]
    }

    /// The graph chosen now, re-read from its file, with `params` (`--param`), the sample
    /// count M chose and, with the overlay, the overlay pass over it.
    pub fn spec(&mut self, params: &[(String, String)]) -> Result<GraphSpec> {
        self.now.overlay = self.overlay;
        let entry = &self.list[self.now.index];
        let base = match entry {
            Entry::Builtin(name) => GraphSpec::builtin(name)?,
            Entry::File(path) => GraphSpec::from_file(path)?,
        };
        let mut overrides = params.to_vec();
        if let Some(samples) = self.msaa {
            overrides.push(("msaa".into(), samples.to_string()));
        }
        let spec = if self.overlay {
            let extends = match entry {
                Entry::Builtin(name) => name.clone(),
                Entry::File(path) => path.display().to_string(),
            };
            let overlay = GraphSpec::builtin("overlay")?;
            let name = format!("{}+overlay", base_name(entry));
            // The shipped overlay graph is the default graph plus its pass: the same text over
            // another base. Refuse plainly should that graph ever be written otherwise.
            let (base_key, name_key) = ("extends: \"default\"", "name: \"overlay\"");
            if !overlay.text.contains(base_key) || !overlay.text.contains(name_key) {
                return Err(cullgraph::Error::Invalid(format!(
                    "{} no longer reads `{base_key}` and `{name_key}`: the viewer cannot compose the overlay over another graph",
                    overlay.file
                )));
            }
            let text = overlay.text.replacen(base_key, &format!("extends: {extends:?}"), 1).replacen(
                name_key,
                &format!("name: {name:?}"),
                1,
            );
            overrides.insert(0, ("overlay_view".into(), self.overlay_view().into()));
            GraphSpec::from_text(&format!("the overlay over {extends}"), text)
        } else {
            base
        };
        Ok(spec.with_overrides(overrides))
    }

    /// The renderer runs the graph chosen now.
    pub fn accepted(&mut self) {
        self.before_good = self.good;
        self.good = self.now;
        self.reloaded_untried = true;
    }

    /// The renderer kept (or went back to) the last good graph: so does the choice.
    pub fn revert(&mut self) {
        if self.reloaded_untried {
            self.good = self.before_good;
            self.reloaded_untried = false;
        }
        self.now = self.good;
        self.overlay = self.good.overlay;
    }
}

/// A short name for the entry: the graph's name or the file's stem.
fn base_name(entry: &Entry) -> String {
    match entry {
        Entry::Builtin(name) => name.clone(),
        Entry::File(path) => path.file_stem().map_or("graph".into(), |s| s.to_string_lossy().into_owned()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn graphs_step_round_the_shipped_ones_and_the_overlay_composes_over_them() {
        let mut choice = GraphChoice::new(None).unwrap();
        assert_eq!(choice.spec(&[]).unwrap().file, GraphSpec::builtin("default").unwrap().file);
        let n = choice.list.len();
        assert!(n >= 10 && choice.list.iter().all(|e| !matches!(e, Entry::Builtin(n) if n.starts_with("shadow"))));
        choice.step(n as isize);
        assert_eq!(choice.now.index, choice.good.index);
        choice.overlay = true;
        choice.next_overlay_view();
        let spec = choice.spec(&[("exposure".into(), "1.5".into())]).unwrap();
        assert!(spec.text.contains("extends: \"default\"") && spec.text.contains("name: \"default+overlay\""));
        assert_eq!(spec.overrides[0], ("overlay_view".to_string(), "hiz".to_string()));
        // Over another graph: the same pass, extending that one.
        let frustum = choice.list.iter().position(|e| *e == Entry::Builtin("frustum".into())).unwrap();
        choice.now.index = frustum;
        let spec = choice.spec(&[]).unwrap();
        assert!(spec.text.contains("extends: \"frustum\"") && spec.text.contains("name: \"frustum+overlay\""));
        choice.now.index = choice.good.index;
        // A choice the renderer refused goes back to the last good one.
        choice.step(1);
        choice.revert();
        assert_eq!((choice.now.index, choice.overlay), (choice.good.index, false));
    }

    #[test]
    fn a_file_comes_first_and_an_unknown_builtin_is_refused() {
        let choice = GraphChoice::new(Some("my/graph.ron")).unwrap();
        assert_eq!(choice.file(), Some("my/graph.ron"));
        assert!(GraphChoice::new(Some("builtin:nope")).is_err());
    }
}
