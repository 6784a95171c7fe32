//! Preview renderer: path tracing and lit spheres for looking at materials.
