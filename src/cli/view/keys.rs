//! The viewer's key bindings: one table gives what a key does, its name in `--script` files and
//! the help overlay's line for it.

use super::fly::Move;

/// What a key does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Fly while held.
    Move(Move),
    /// Move faster while held (with G and C: the other way through the list).
    Shift,
    /// Show or hide the help overlay.
    Help,
    /// The culling-stat overlay on or off.
    Overlay,
    /// The overlay's next view: stats, hiz, culled.
    OverlayView,
    /// The next graph (Shift: the previous one).
    NextGraph,
    /// The previous graph.
    PreviousGraph,
    /// The graph's next MSAA sample count.
    Msaa,
    /// Shadows on or off.
    Shadows,
    /// Freeze the culling where it is, or let it follow the camera again.
    Freeze,
    /// The city's traffic on or off.
    Traffic,
    /// Reload the graph and shaders now.
    Reload,
    /// Write the presented image to a PNG file.
    Screenshot,
    /// The next spawn point (Shift: the previous one).
    NextSpawn,
    /// Close the window.
    Quit,
}

/// Every key the viewer knows: its name (as `--script` spells it, case-insensitive) and action.
pub const KEYS: &[(&str, Action)] = &[
    ("W", Action::Move(Move::Forward)),
    ("Up", Action::Move(Move::Forward)),
    ("S", Action::Move(Move::Back)),
    ("Down", Action::Move(Move::Back)),
    ("A", Action::Move(Move::Left)),
    ("Left", Action::Move(Move::Left)),
    ("D", Action::Move(Move::Right)),
    ("Right", Action::Move(Move::Right)),
    ("E", Action::Move(Move::Up)),
    ("Space", Action::Move(Move::Up)),
    ("Q", Action::Move(Move::Down)),
    ("Shift", Action::Shift),
    ("H", Action::Help),
    ("F1", Action::Help),
    ("O", Action::Overlay),
    ("V", Action::OverlayView),
    ("G", Action::NextGraph),
    ("PageDown", Action::NextGraph),
    ("PageUp", Action::PreviousGraph),
    ("M", Action::Msaa),
    ("L", Action::Shadows),
    ("F", Action::Freeze),
    ("T", Action::Traffic),
    ("R", Action::Reload),
    ("P", Action::Screenshot),
    ("F12", Action::Screenshot),
    ("C", Action::NextSpawn),
    ("Escape", Action::Quit),
];

/// The help overlay's lines: keys, then what they do.
pub const HELP: &[(&str, &str)] = &[
    ("W A S D, arrows", "fly; E/Space up, Q down"),
    ("Shift", "fly 4x faster"),
    ("mouse drag", "look around (either button)"),
    ("mouse wheel", "flying speed"),
    ("C / Shift+C", "next / previous spawn point"),
    ("O", "culling-stat overlay on/off"),
    ("V", "overlay view: stats, hiz, culled"),
    ("G / Shift+G", "next / previous graph (PgDn/PgUp)"),
    ("M", "MSAA samples (MSAA graphs)"),
    ("L", "shadows on/off"),
    ("F", "freeze culling; fly on to see what was culled"),
    ("T", "traffic on/off (builtin:city)"),
    ("R", "reload graph and shaders (also on save)"),
    ("P, F12", "screenshot"),
    ("H, F1", "this help"),
    ("Esc", "quit"),
];

/// The action of the key called `name` (case-insensitive).
pub fn action_named(name: &str) -> Option<Action> {
    KEYS.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)).map(|(_, a)| *a)
}

/// The name of a winit key, as [`KEYS`] spells it; `None` for keys the viewer ignores.
pub fn key_name(key: &winit::keyboard::Key) -> Option<String> {
    use winit::keyboard::{Key, NamedKey};
    Some(match key {
        Key::Character(c) => c.to_ascii_uppercase(),
        Key::Named(named) => match named {
            NamedKey::ArrowUp => "Up",
            NamedKey::ArrowDown => "Down",
            NamedKey::ArrowLeft => "Left",
            NamedKey::ArrowRight => "Right",
            NamedKey::Space => "Space",
            NamedKey::Shift => "Shift",
            NamedKey::F1 => "F1",
            NamedKey::F12 => "F12",
            NamedKey::PageUp => "PageUp",
            NamedKey::PageDown => "PageDown",
            NamedKey::Escape => "Escape",
            _ => return None,
        }
        .to_string(),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_has_a_unique_name_and_names_match_in_any_case() {
        for (i, (name, action)) in KEYS.iter().enumerate() {
            assert!(KEYS[..i].iter().all(|(n, _)| !n.eq_ignore_ascii_case(name)), "{name} twice");
            assert_eq!(action_named(&name.to_lowercase()), Some(*action));
        }
        assert_eq!(action_named("Z"), None);
    }
}
