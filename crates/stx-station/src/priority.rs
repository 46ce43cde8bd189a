//! Work that must never delay the flight runs at the lowest priority: the Lab's jobs on the
//! station, and a public relay beside it. Measured on this two-core machine: nice 19 alone
//! left `stx bench station --lab-montecarlo 100`'s telemetry p99 at 12.2 and 11.6 ms (8.1
//! and 7.7 without the Lab); with the idle class too, 6.2 and 7.6 ms.

/// The nice value given: the lowest priority.
pub const LOWEST_NICE: i32 = 19;

/// Lowers the calling thread (not the process: Linux schedules each thread on its own) to
/// [`LOWEST_NICE`] and the idle scheduling class; threads it starts inherit both. The class is
/// what matters on Linux's EEVDF scheduler (6.6 on): a thread of any nice value runs out its
/// slice before a woken one gets the core, while a thread of the idle class is preempted by
/// any other the moment it wakes. Elsewhere, or when refused, `what` runs at the usual
/// priority and the log says so.
pub fn lower_this_thread(what: &str) {
    #[cfg(target_os = "linux")]
    {
        let param = libc::sched_param { sched_priority: 0 };
        // SAFETY: gettid, setpriority and sched_setscheduler only read and set the calling
        // thread's scheduling attributes; `param` lives across the call.
        let refused = unsafe {
            let tid = libc::gettid();
            libc::setpriority(libc::PRIO_PROCESS, tid as libc::id_t, LOWEST_NICE) != 0
                || libc::sched_setscheduler(0, libc::SCHED_IDLE, &param) != 0
        };
        if refused {
            tracing::warn!(
                error = %std::io::Error::last_os_error(),
                "{what} runs at the usual priority"
            );
        }
    }
    #[cfg(not(target_os = "linux"))]
    tracing::warn!("{what} runs at the usual priority (Linux only lowers it)");
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::{LOWEST_NICE, lower_this_thread};

    /// The nice value of the calling thread, from `/proc/thread-self/stat` (field 19).
    fn nice_of_this_thread() -> i32 {
        let stat = std::fs::read_to_string("/proc/thread-self/stat").expect("stat");
        // The command name (field 2) may hold spaces; the fields after it do not.
        let after_name = &stat[stat.rfind(')').expect("name") + 2..];
        after_name
            .split(' ')
            .nth(16)
            .expect("nice")
            .parse()
            .expect("a number")
    }

    #[test]
    fn a_lowered_thread_and_those_it_starts_run_at_the_lowest_priority_alone() {
        let before = nice_of_this_thread();
        // SAFETY: sched_getscheduler(0) only reads the calling thread's policy.
        let policy = || unsafe { libc::sched_getscheduler(0) };
        let both = move || (nice_of_this_thread(), policy());
        let (own, started) = std::thread::spawn(move || {
            lower_this_thread("the test");
            let started = std::thread::spawn(both).join().expect("joins");
            (both(), started)
        })
        .join()
        .expect("joins");
        let lowest = (LOWEST_NICE, libc::SCHED_IDLE);
        assert_eq!((own, started), (lowest, lowest));
        assert_ne!(policy(), libc::SCHED_IDLE, "the other threads keep theirs");
        assert_eq!(
            nice_of_this_thread(),
            before,
            "the other threads keep theirs"
        );
    }
}
