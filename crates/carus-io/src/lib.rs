//! Mesh input and result output.
