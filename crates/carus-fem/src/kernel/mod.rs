//! The CPU kernels of the step loop and the data layout they read.
//! `lanes`: scalar and 8-lane number types; `element`: the element maths,
//! written once; `blocks`: the structure-of-arrays model data; `passes`:
//! the parallel passes of a step.

pub mod blocks;
pub mod element;
pub mod lanes;
pub mod passes;
pub mod stability;
