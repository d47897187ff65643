//! The software rasterizer. It knows nothing about fur.
