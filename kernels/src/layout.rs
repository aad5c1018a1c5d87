//! GPU data layouts shared by the kernels and the host: declared once, in `cohort-layout`,
//! which the scene builder writes and the kernels read.

pub use cohort_layout::*;
