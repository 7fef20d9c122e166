//! The tracer side: the render thread and its pool (`worker`), what it is asked to trace and hands back
//! (`jobs`), the live method comparison (`compare`), and its threads' scheduling priority (`priority`).

pub mod compare;
pub mod jobs;
pub mod priority;
pub mod worker;
