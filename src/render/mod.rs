//! Assembles one frame: base mesh, shells layer by layer, fins.
