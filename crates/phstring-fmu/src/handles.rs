//! The handles the C functions give the master for instances (`fmi2Component`,
//! `fmi3Instance`) and saved states (`fmi2FMUstate`, `fmi3FMUState`).
//!
//! A handle is a number from a counter, never reused, that the master holds as an opaque
//! pointer; the library never dereferences it. The objects live in registries keyed by
//! handle, so a handle that was freed or never given out (a second `fmi2FreeInstance`, a
//! state used after `fmi2FreeFMUstate`, a wild pointer) is found missing and the call is
//! refused, instead of reading freed memory. Each instance sits behind its own mutex: calls
//! on one instance from several threads run one at a time, calls on different instances in
//! parallel (the registries' locks are held only to look a handle up).

use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, LazyLock, Mutex};

use crate::instance::{Instance, Saved, lock};

/// An instance as the registry holds it: shared with the calls running on it, so that a
/// `fmi2FreeInstance` during a call (from another thread) frees it when that call ends.
pub(crate) type SharedInstance = Arc<Mutex<Instance>>;

/// A saved state and the handle of the instance that saved it (its states go with it).
struct State {
    owner: usize,
    saved: Arc<Saved>,
}

static INSTANCES: LazyLock<Mutex<HashMap<usize, SharedInstance>>> = LazyLock::new(Default::default);
static STATES: LazyLock<Mutex<HashMap<usize, State>>> = LazyLock::new(Default::default);
static NEXT: AtomicUsize = AtomicUsize::new(1);

/// A handle not given out before: a multiple of 16 (aligned like an allocation, for masters
/// that check), never 0.
fn fresh() -> usize {
    NEXT.fetch_add(1, Ordering::Relaxed) * 16
}

/// Registers `inst`; its handle.
pub(crate) fn add_instance(inst: Instance) -> usize {
    let h = fresh();
    lock(&INSTANCES).insert(h, Arc::new(Mutex::new(inst)));
    h
}

/// Unregisters instance `h` and the states it saved (each is dropped once no call uses it);
/// false if `h` is not a live instance.
pub(crate) fn remove_instance(h: usize) -> bool {
    let removed = lock(&INSTANCES).remove(&h).is_some();
    if removed {
        lock(&STATES).retain(|_, s| s.owner != h);
    }
    removed
}

/// Instance `h`, if it is live.
pub(crate) fn instance(h: usize) -> Option<SharedInstance> {
    lock(&INSTANCES).get(&h).cloned()
}

/// Registers `saved`, saved by instance `owner`; its handle.
pub(crate) fn add_state(owner: usize, saved: Saved) -> usize {
    let h = fresh();
    let saved = Arc::new(saved);
    lock(&STATES).insert(h, State { owner, saved });
    h
}

/// Replaces the content of state `h` (FMI reuses a state passed back to `GetFMUstate`);
/// false if `h` is not a live state.
pub(crate) fn replace_state(h: usize, saved: Saved) -> bool {
    match lock(&STATES).get_mut(&h) {
        Some(s) => {
            s.saved = Arc::new(saved);
            true
        }
        None => false,
    }
}

/// State `h`, if it is live.
pub(crate) fn state(h: usize) -> Option<Arc<Saved>> {
    lock(&STATES).get(&h).map(|s| s.saved.clone())
}

/// Unregisters state `h`; false if it is not a live state.
pub(crate) fn remove_state(h: usize) -> bool {
    lock(&STATES).remove(&h).is_some()
}

thread_local! {
    /// The instances this thread is in a call on.
    static ENTERED: RefCell<Vec<usize>> = const { RefCell::new(Vec::new()) };
}

/// Marks this thread as in a call on an instance until dropped.
pub(crate) struct Entered(usize);

impl Entered {
    /// Enters instance `h`; `None` if this thread is already in a call on it (the master
    /// called back from its logger: waiting for the instance's lock would never end).
    pub(crate) fn new(h: usize) -> Option<Self> {
        ENTERED.with(|e| {
            let mut e = e.borrow_mut();
            if e.contains(&h) {
                None
            } else {
                e.push(h);
                Some(Self(h))
            }
        })
    }
}

impl Drop for Entered {
    fn drop(&mut self) {
        ENTERED.with(|e| e.borrow_mut().retain(|&x| x != self.0));
    }
}
