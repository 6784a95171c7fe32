//! The brdftab file format and database of named tables.
