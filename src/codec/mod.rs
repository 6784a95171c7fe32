//! Compression codecs: f32 arrays in, bytes out (knows nothing about BRDFs).
