//! The parametric asset library: household object categories, their shape variants and the
//! material table.
