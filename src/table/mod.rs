//! Dense 5D tables: grids, symmetry reduction, baking, interpolated lookup.
