//! The thread CPU time advances with the calling thread's work, never faster than the wall clock, and not
//! while the thread sleeps.

use std::hint::black_box;
use std::time::{Duration, Instant};

use stride_testkit::thread_cpu_time;

#[test]
fn advances_with_work_and_not_with_sleep() {
    let c0 = thread_cpu_time().expect("CLOCK_THREAD_CPUTIME_ID");
    std::thread::sleep(Duration::from_millis(50));
    let c1 = thread_cpu_time().unwrap();
    assert!(
        c1 - c0 < Duration::from_millis(25),
        "asleep 50 ms, CPU time {:?}",
        c1 - c0
    );
    // Busy work until 10 ms of CPU time have passed (however loaded the machine), within 10 s of wall
    // clock, which those 10 ms cannot exceed.
    let w0 = Instant::now();
    let c1 = thread_cpu_time().unwrap();
    let (mut x, mut c2) = (0_u64, c1);
    while c2 - c1 < Duration::from_millis(10) && w0.elapsed() < Duration::from_secs(10) {
        for _ in 0..1000 {
            x = black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        c2 = thread_cpu_time().unwrap();
    }
    let wall = w0.elapsed();
    assert!(
        c2 - c1 >= Duration::from_millis(10),
        "busy for {wall:?}, CPU time only {:?}",
        c2 - c1
    );
    assert!(c2 - c1 <= wall, "busy for {wall:?}, CPU time {:?}", c2 - c1);
}
