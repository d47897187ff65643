//! Fur modelling (thesis 3.1): strands, cones, and baked shell and fin textures.
