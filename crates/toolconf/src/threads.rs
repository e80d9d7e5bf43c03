//! The size of rayon's thread pool, for the command line and the Python package.
//!
//! `RAYON_NUM_THREADS` asks for a number of threads; asked for thousands, rayon would start them
//! all (seconds before any work, and memory for every stack) although only the cores compute.
//! The pool is capped at [`THREADS_PER_CORE`] threads per core. Results do not depend on the
//! number of threads, so the cap changes the run time only.

/// The most threads per core the pool is given.
pub const THREADS_PER_CORE: usize = 4;

/// Builds rayon's global pool with at most [`THREADS_PER_CORE`] × the cores when
/// `RAYON_NUM_THREADS` asks for more, and says so; otherwise leaves rayon to its own reading of
/// the variable (one thread per core by default). Call it before any parallel work.
pub fn cap_pool() -> Option<String> {
    let requested: usize = std::env::var("RAYON_NUM_THREADS")
        .ok()?
        .trim()
        .parse()
        .ok()?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let cap = THREADS_PER_CORE * cores;
    if requested <= cap {
        return None;
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(cap)
        .build_global()
        .ok()?;
    Some(format!(
        "RAYON_NUM_THREADS={requested} is more than {THREADS_PER_CORE} threads for each of the \
         {cores} cores; using {cap}"
    ))
}
