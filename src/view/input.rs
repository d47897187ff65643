//! Input → actions: which key or mouse gesture does what. Pure functions of the input, so the
//! whole mapping is unit-tested without a window.

use minifb::Key;

/// Arrow keys orbit by this many radians (5°) per press or repeat.
pub const ORBIT_STEP: f32 = 5.0 * std::f32::consts::PI / 180.0;
/// Shift + arrow keys pan by this many pixels per press or repeat.
pub const PAN_STEP: f32 = 20.0;
/// `+` / `-` and one notch of the wheel multiply the camera distance by this (or its inverse).
pub const ZOOM_STEP: f32 = 1.1;
/// A drag across the whole window width orbits half a turn.
pub const ORBIT_PER_WIDTH: f32 = std::f32::consts::PI;

/// Something the user asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// Turn the camera around its target (radians: around the up axis, then towards it).
    Orbit {
        /// Around the up axis, counter-clockwise seen from above.
        yaw: f32,
        /// Towards the up axis.
        pitch: f32,
    },
    /// Slide the camera so the scene follows a drag of this many pixels (y down).
    Pan {
        /// Pixels right.
        dx: f32,
        /// Pixels down.
        dy: f32,
    },
    /// Multiply the camera's distance to its target.
    Zoom(f32),
    /// Back to the scene's own camera.
    ResetCamera,
    /// Wind on or off.
    ToggleWind,
    /// Light the matches now.
    StartBurn,
    /// Put the fire out: unburnt fur.
    ResetBurn,
    /// Spots and stripes on or off.
    ToggleSpots,
    /// Level of detail (`[lod]`: fewer shells as the fur gets small) on or off.
    ToggleLod,
    /// Gravity (`[gravity]`: the fur hangs) on or off.
    ToggleGravity,
    /// The scene's surface maps (`[maps]`: length, density, direction, colour) on or off
    /// (rebakes).
    ToggleMaps,
    /// Change the number of shells by this much (rebakes).
    Shells(i32),
    /// Double (+1) or halve (−1) the shell texture resolution (rebakes).
    TextureResolution(i32),
    /// Next (+1) or previous (−1) debug view: none, tangents, alpha, shadow.
    DebugView(i32),
    /// Stop or restart the clock.
    TogglePause,
    /// Back to the scene's own time.
    RestartTime,
    /// Write a full-resolution PNG and its scene.
    Screenshot,
    /// Show or hide the key list.
    ToggleHelp,
    /// Close the viewer.
    Quit,
}

/// The key list shown by `h` and printed in the README: keys, then what they do.
pub const KEYS: &[(&str, &str)] = &[
    ("Left drag, arrows", "orbit"),
    ("Right drag, Shift + arrows", "pan"),
    ("Wheel, + −", "zoom"),
    ("R, Home", "reset the camera"),
    ("W", "wind on/off"),
    ("B / N", "start burning now / put the fire out"),
    ("S", "spots and stripes on/off"),
    ("L", "level of detail on/off"),
    ("G", "gravity on/off"),
    ("M", "surface maps on/off (rebakes)"),
    ("[ ]  (Shift: by 10)", "fewer/more shells (rebakes)"),
    (", .", "halve/double texture resolution (rebakes)"),
    (
        "V, Shift + V",
        "debug view: shaded, tangents, alpha, shadow",
    ),
    ("Space", "pause/run time"),
    ("T, Backspace", "back to the scene's time"),
    ("P, F12", "screenshot: full-resolution PNG + scene TOML"),
    ("H, F1", "this key list"),
    ("Q, Esc", "quit"),
];

/// The action of a key press. `shift`: a shift key is held; `repeated`: the press is the
/// keyboard's auto-repeat, which moves the camera and steps counts but never flips a toggle.
pub fn key_action(key: Key, shift: bool, repeated: bool) -> Option<Action> {
    let continuous = match key {
        Key::Left if shift => Some(Action::Pan {
            dx: -PAN_STEP,
            dy: 0.0,
        }),
        Key::Right if shift => Some(Action::Pan {
            dx: PAN_STEP,
            dy: 0.0,
        }),
        Key::Up if shift => Some(Action::Pan {
            dx: 0.0,
            dy: -PAN_STEP,
        }),
        Key::Down if shift => Some(Action::Pan {
            dx: 0.0,
            dy: PAN_STEP,
        }),
        Key::Left => Some(Action::Orbit {
            yaw: -ORBIT_STEP,
            pitch: 0.0,
        }),
        Key::Right => Some(Action::Orbit {
            yaw: ORBIT_STEP,
            pitch: 0.0,
        }),
        Key::Up => Some(Action::Orbit {
            yaw: 0.0,
            pitch: ORBIT_STEP,
        }),
        Key::Down => Some(Action::Orbit {
            yaw: 0.0,
            pitch: -ORBIT_STEP,
        }),
        Key::Equal | Key::NumPadPlus | Key::PageUp => Some(Action::Zoom(1.0 / ZOOM_STEP)),
        Key::Minus | Key::NumPadMinus | Key::PageDown => Some(Action::Zoom(ZOOM_STEP)),
        Key::LeftBracket => Some(Action::Shells(if shift { -10 } else { -1 })),
        Key::RightBracket => Some(Action::Shells(if shift { 10 } else { 1 })),
        Key::Comma => Some(Action::TextureResolution(-1)),
        Key::Period => Some(Action::TextureResolution(1)),
        _ => None,
    };
    if continuous.is_some() {
        return continuous;
    }
    if repeated {
        return None;
    }
    match key {
        Key::R | Key::Home => Some(Action::ResetCamera),
        Key::W => Some(Action::ToggleWind),
        Key::B => Some(Action::StartBurn),
        Key::N => Some(Action::ResetBurn),
        Key::S => Some(Action::ToggleSpots),
        Key::L => Some(Action::ToggleLod),
        Key::G => Some(Action::ToggleGravity),
        Key::M => Some(Action::ToggleMaps),
        Key::V => Some(Action::DebugView(if shift { -1 } else { 1 })),
        Key::Space => Some(Action::TogglePause),
        Key::T | Key::Backspace => Some(Action::RestartTime),
        Key::P | Key::F12 => Some(Action::Screenshot),
        Key::H | Key::F1 => Some(Action::ToggleHelp),
        Key::Q | Key::Escape => Some(Action::Quit),
        _ => None,
    }
}

/// Key events in the order the window system delivered them → actions. Every press is acted
/// on, however short (a tap pressed and released between two frames still counts); a press of
/// a key already held is the keyboard's auto-repeat (X11 reports repeats as presses without
/// releases), which repeats continuous actions but never flips a toggle twice. Shift is the
/// state of the shift keys at the moment of the press.
#[derive(Clone, Debug, Default)]
pub struct KeyTracker {
    held: Vec<Key>,
}

impl KeyTracker {
    /// The action of one event: `down` a press, else a release.
    pub fn event(&mut self, key: Key, down: bool) -> Option<Action> {
        if !down {
            self.held.retain(|k| *k != key);
            return None;
        }
        let repeated = self.held.contains(&key);
        if !repeated {
            self.held.push(key);
        }
        let shift = self.held.contains(&Key::LeftShift) || self.held.contains(&Key::RightShift);
        key_action(key, shift, repeated)
    }

    /// The actions of a batch of events, in order.
    pub fn events(&mut self, events: impl IntoIterator<Item = (Key, bool)>) -> Vec<Action> {
        events
            .into_iter()
            .filter_map(|(key, down)| self.event(key, down))
            .collect()
    }

    /// Forgets every held key (the window lost focus: releases may never come).
    pub fn clear(&mut self) {
        self.held.clear();
    }
}

/// Which mouse button drags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drag {
    /// Left button: orbit.
    Orbit,
    /// Right or middle button: pan.
    Pan,
}

/// The action of a mouse drag from `from` to `to` (window pixels) in a window `width` wide.
pub fn drag_action(drag: Drag, from: (f32, f32), to: (f32, f32), width: f32) -> Option<Action> {
    let (dx, dy) = (to.0 - from.0, to.1 - from.1);
    if dx == 0.0 && dy == 0.0 || !(dx.is_finite() && dy.is_finite()) {
        return None;
    }
    Some(match drag {
        // Dragging right turns the object right: the eye goes the other way round.
        Drag::Orbit => {
            let per_pixel = ORBIT_PER_WIDTH / width.max(1.0);
            Action::Orbit {
                yaw: -dx * per_pixel,
                pitch: dy * per_pixel,
            }
        }
        Drag::Pan => Action::Pan { dx, dy },
    })
}

/// The action of the wheel turned by `notches` (positive: away from the user, zoom in).
pub fn wheel_action(notches: f32) -> Option<Action> {
    (notches != 0.0 && notches.is_finite()).then(|| Action::Zoom(ZOOM_STEP.powf(-notches)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrows_orbit_and_shift_arrows_pan_even_when_repeated() {
        for repeated in [false, true] {
            assert_eq!(
                key_action(Key::Left, false, repeated),
                Some(Action::Orbit {
                    yaw: -ORBIT_STEP,
                    pitch: 0.0
                })
            );
            assert_eq!(
                key_action(Key::Up, true, repeated),
                Some(Action::Pan {
                    dx: 0.0,
                    dy: -PAN_STEP
                })
            );
        }
    }

    #[test]
    fn toggles_fire_once_per_press_not_on_auto_repeat() {
        assert_eq!(key_action(Key::W, false, false), Some(Action::ToggleWind));
        assert_eq!(key_action(Key::W, false, true), None);
        assert_eq!(key_action(Key::Space, false, true), None);
        assert_eq!(key_action(Key::P, false, true), None);
    }

    #[test]
    fn every_documented_action_has_a_key() {
        let keys = [
            Key::Left,
            Key::Up,
            Key::Equal,
            Key::Minus,
            Key::R,
            Key::W,
            Key::B,
            Key::N,
            Key::S,
            Key::LeftBracket,
            Key::RightBracket,
            Key::Comma,
            Key::Period,
            Key::V,
            Key::Space,
            Key::T,
            Key::P,
            Key::H,
            Key::Q,
            Key::Escape,
        ];
        for key in keys {
            assert!(key_action(key, false, false).is_some(), "{key:?}");
        }
        assert_eq!(
            key_action(Key::RightBracket, true, false),
            Some(Action::Shells(10))
        );
        assert_eq!(key_action(Key::V, true, false), Some(Action::DebugView(-1)));
        assert_eq!(key_action(Key::Z, false, false), None);
        assert_eq!(key_action(Key::L, false, false), Some(Action::ToggleLod));
        assert_eq!(
            key_action(Key::G, false, false),
            Some(Action::ToggleGravity)
        );
        assert_eq!(key_action(Key::M, false, false), Some(Action::ToggleMaps));
        assert_eq!(key_action(Key::M, false, true), None);
        assert!(KEYS.iter().all(|(k, d)| !k.is_empty() && !d.is_empty()));
    }

    #[test]
    fn dragging_right_turns_the_eye_clockwise_and_a_full_width_is_half_a_turn() {
        let a = drag_action(Drag::Orbit, (0.0, 10.0), (640.0, 10.0), 640.0);
        assert_eq!(
            a,
            Some(Action::Orbit {
                yaw: -std::f32::consts::PI,
                pitch: 0.0
            })
        );
        assert_eq!(
            drag_action(Drag::Pan, (5.0, 5.0), (8.0, 1.0), 640.0),
            Some(Action::Pan { dx: 3.0, dy: -4.0 })
        );
        assert_eq!(
            drag_action(Drag::Orbit, (1.0, 1.0), (1.0, 1.0), 640.0),
            None
        );
    }

    #[test]
    fn the_wheel_zooms_in_away_from_the_user() {
        let Some(Action::Zoom(f)) = wheel_action(1.0) else {
            panic!("no zoom");
        };
        assert!((f - 1.0 / ZOOM_STEP).abs() < 1e-6);
        assert_eq!(wheel_action(0.0), None);
    }

    #[test]
    fn a_tap_between_two_frames_is_never_lost() {
        // Pressed and released before the next frame polls: one toggle, acted on.
        let mut keys = KeyTracker::default();
        let actions = keys.events([(Key::W, true), (Key::W, false)]);
        assert_eq!(actions, vec![Action::ToggleWind]);
        // Two taps in one frame: two toggles (wind back off).
        let actions = keys.events([
            (Key::W, true),
            (Key::W, false),
            (Key::W, true),
            (Key::W, false),
        ]);
        assert_eq!(actions, vec![Action::ToggleWind, Action::ToggleWind]);
    }

    #[test]
    fn auto_repeat_repeats_moves_but_not_toggles_and_shift_is_read_at_the_press() {
        let mut keys = KeyTracker::default();
        // Held W: the repeats (presses without a release) flip nothing.
        let actions = keys.events([(Key::W, true), (Key::W, true), (Key::W, true)]);
        assert_eq!(actions, vec![Action::ToggleWind]);
        // Held Left: every repeat orbits.
        let actions = keys.events([(Key::Left, true), (Key::Left, true), (Key::Left, false)]);
        assert_eq!(actions.len(), 2);
        // Shift pressed, an arrow tapped, shift released in one frame: a pan.
        let actions = keys.events([
            (Key::LeftShift, true),
            (Key::Up, true),
            (Key::Up, false),
            (Key::LeftShift, false),
            (Key::Up, true),
        ]);
        assert_eq!(
            actions,
            vec![
                Action::Pan {
                    dx: 0.0,
                    dy: -PAN_STEP
                },
                Action::Orbit {
                    yaw: 0.0,
                    pitch: ORBIT_STEP
                }
            ]
        );
        // After focus is lost, the next press of a held key is fresh again.
        keys.clear();
        assert_eq!(keys.event(Key::W, true), Some(Action::ToggleWind));
    }
}
