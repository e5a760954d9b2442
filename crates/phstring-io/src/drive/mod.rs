//! The command drivers, the top floor of the crate: each runs one `phstring` command from a
//! scenario to the files of its output folder. Nothing else in the crate imports them.
//!
//! * [`run`]: a simulation (`phstring run`), with checkpoints and resume;
//! * [`statics`]: the equilibrium (`phstring statics`);
//! * [`at`]: the system as a run's checkpoint holds it (`statics --at`, `linearize --at`);
//! * [`modes`]: the natural modes about it (`phstring modes`);
//! * [`linearize`]: the linear model (`phstring linearize`);
//! * [`mooring`]: a rigid body's mooring stiffness and offset–tension curve (`phstring
//!   mooring`);
//! * [`sweep`]: many runs over varied parameters (`phstring sweep`);
//! * [`campaign`]: the extremes of a run's lines and a sweep's campaign table;
//! * [`outdir`]: preparing and locking an output folder;
//! * [`water`]: the `water` part of a run's summary.

pub mod at;
pub mod campaign;
pub mod ends;
pub mod linearize;
pub mod modes;
pub mod mooring;
pub mod outdir;
pub mod run;
pub mod statics;
pub mod sweep;
pub mod water;
