//! The shading terms of the thesis (3.2–3.4) as small pure functions.
