//! `--script FILE`: timed input played into the viewer, for tests and recorded fly-throughs.
//!
//! One event a line, `FRAME EVENT...`, events of one frame in file order, `#` starts a comment:
//!
//! ```text
//! 10 key W down        # a key of the bindings (see `keys.rs`) goes down or up
//! 40 key W up
//! 50 press O           # down and up in the same frame
//! 60 look 120 -30      # the mouse drags the view by dx, dy pixels (right, down)
//! 70 wheel 2           # wheel notches (flying speed x 1.25 each)
//! 80 resize 640x360    # the window asks for this size
//! ```
//!
//! Time is counted in presented frames, and a scripted run advances 1/60 s a frame, so that a
//! script moves the camera the same way on every machine.

use super::keys::{action_named, Action};
use cullgraph::{Error, Result};

/// Seconds a frame of a scripted run advances.
pub const SCRIPTED_FRAME_SECONDS: f64 = 1.0 / 60.0;

/// One input event.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// A key went down (`true`) or up.
    Key(Action, bool),
    /// A drag of the view by (dx, dy) pixels.
    Look(f64, f64),
    /// Wheel notches (positive: faster).
    Wheel(f64),
    /// The window asks for this size.
    Resize(u32, u32),
}

/// The events of a script, by frame.
#[derive(Clone, Debug, Default)]
pub struct Script {
    events: Vec<(u64, Event)>,
    /// The next event to play.
    next: usize,
}

impl Script {
    /// Reads and checks `path`; errors name `path:line`.
    pub fn load(path: &std::path::Path) -> Result<Self> {
        let text = cullgraph::files::read_limited_text(path, cullgraph::files::GRAPH_LIMIT, "script")
            .map_err(|e| Error::Io { path: path.display().to_string(), source: std::io::Error::other(e) })?;
        Self::parse(&path.display().to_string(), &text)
    }

    /// Parses script text; errors name `file:line`.
    pub fn parse(file: &str, text: &str) -> Result<Self> {
        let mut events = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let at = |why: String| Error::Invalid(format!("{file}:{}: {why}", n + 1));
            let words: Vec<&str> = line.split_whitespace().collect();
            let frame: u64 = words[0].parse().map_err(|_| at(format!("'{}' is not a frame number", words[0])))?;
            if events.last().is_some_and(|(f, _)| *f > frame) {
                return Err(at(format!("frame {frame} comes before the previous line's")));
            }
            let number = |i: usize| -> Result<f64> {
                let word = words.get(i).ok_or_else(|| at(format!("'{line}' lacks a number")))?;
                word.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() && v.abs() <= 1e6)
                    .ok_or_else(|| at(format!("'{word}' is not a number from -1e6 to 1e6")))
            };
            let key = |i: usize| -> Result<Action> {
                let name = words.get(i).ok_or_else(|| at("a key name is missing".into()))?;
                action_named(name).ok_or_else(|| at(format!("unknown key '{name}'")))
            };
            let (event, arity) = match words.get(1).copied() {
                Some("key") => {
                    let down = match words.get(3).copied() {
                        Some("down") => true,
                        Some("up") => false,
                        _ => return Err(at("`key NAME` takes `down` or `up`".into())),
                    };
                    (vec![Event::Key(key(2)?, down)], 4)
                }
                Some("press") => {
                    let action = key(2)?;
                    (vec![Event::Key(action, true), Event::Key(action, false)], 3)
                }
                Some("look") => (vec![Event::Look(number(2)?, number(3)?)], 4),
                Some("wheel") => (vec![Event::Wheel(number(2)?)], 3),
                Some("resize") => {
                    let size = words.get(2).ok_or_else(|| at("`resize` takes WIDTHxHEIGHT".into()))?;
                    let (w, h) = super::super::args::parse_size(size).map_err(at)?;
                    (vec![Event::Resize(w, h)], 3)
                }
                other => {
                    return Err(at(format!(
                        "unknown event '{}' (key, press, look, wheel or resize)",
                        other.unwrap_or("")
                    )))
                }
            };
            if words.len() > arity {
                return Err(at(format!("'{}' is more than the event takes", words[arity..].join(" "))));
            }
            events.extend(event.into_iter().map(|e| (frame, e)));
        }
        Ok(Self { events, next: 0 })
    }

    /// The events of frames up to `frame` not played yet.
    pub fn due(&mut self, frame: u64) -> Vec<Event> {
        let start = self.next;
        while self.events.get(self.next).is_some_and(|(f, _)| *f <= frame) {
            self.next += 1;
        }
        self.events[start..self.next].iter().map(|(_, e)| e.clone()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::super::fly::Move;
    use super::*;

    #[test]
    fn a_script_plays_its_events_by_frame() {
        let text = "# fly\n2 key w down\n2 look 10 -5 # turn\n5 key W up\n6 press o\n7 wheel -1\n9 resize 320x200\n";
        let mut script = Script::parse("s.txt", text).unwrap();
        assert!(script.due(1).is_empty());
        assert_eq!(script.due(3), [Event::Key(Action::Move(Move::Forward), true), Event::Look(10.0, -5.0)]);
        assert_eq!(
            script.due(6),
            [
                Event::Key(Action::Move(Move::Forward), false),
                Event::Key(Action::Overlay, true),
                Event::Key(Action::Overlay, false)
            ]
        );
        assert_eq!(script.due(100), [Event::Wheel(-1.0), Event::Resize(320, 200)]);
        assert!(script.due(200).is_empty());
    }

    #[test]
    fn bad_lines_are_named_by_file_and_line() {
        for (text, want) in [
            ("1 key Z down", "s.txt:1: unknown key 'Z'"),
            ("x key W down", "s.txt:1: 'x' is not a frame number"),
            ("\n1 key W sideways", "s.txt:2: `key NAME` takes `down` or `up`"),
            ("1 look 1 nan", "s.txt:1: 'nan' is not a number"),
            ("1 jump", "s.txt:1: unknown event 'jump'"),
            ("5 press O\n3 press O", "s.txt:2: frame 3 comes before"),
            ("1 resize 0x10", "s.txt:1: width 0"),
            ("1 wheel 1 2", "s.txt:1: '2' is more than the event takes"),
        ] {
            let e = Script::parse("s.txt", text).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }
}
