//! Concurrent use of one database and one opened table: writers that add at the same time (the
//! database's writer lock), through the file's name and through a symbolic link to it; readers
//! that see the old state or the new one, never a broken one; one table evaluated and sampled
//! from many threads as from one.
//!
//! The writer lock is `File::lock` (an advisory `flock` on an open file description on Unix,
//! `LockFileEx` on a handle on Windows), so threads that each open the lock file exclude each
//! other as processes do. Symbolic links are exercised on Unix only.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use brdftab::codec::{Codec, Quant};
use brdftab::store::{Source, Store, TableHeader, db};
use brdftab::testkit::{Pcg32, TempDir};
use brdftab::{Brdf, Channels};
use glam::{DVec2, DVec3};

const SHAPE: [usize; 4] = [8, 16, 32, 3];

fn values(seed: usize) -> Vec<f32> {
    (0..SHAPE.iter().product::<usize>())
        .map(|i| (((i + seed) % 97) as f32 * 0.37).sin().abs() + 0.01)
        .collect()
}

fn add(path: &Path, name: &str, seed: usize) {
    let header = TableHeader::new(
        name,
        Source::Other {
            description: "concurrency test".into(),
        },
        SHAPE.iter().map(|&n| n as u64).collect(),
        Channels::Rgb,
        Codec {
            quant: Quant::F16,
            level: 1,
            ..Codec::default()
        },
    );
    let data = values(seed);
    db::put(path, header, false, |w| {
        for c in data.chunks(SHAPE[1] * SHAPE[2] * SHAPE[3]) {
            w.chunk(c)?;
        }
        Ok(())
    })
    .unwrap_or_else(|e| panic!("add {name}: {e}"));
}

fn names(path: &Path) -> Vec<String> {
    let s = Store::open(path).expect("the database always opens");
    s.tables().iter().map(|t| t.name.clone()).collect()
}

#[test]
fn adds_from_many_writers_at_once_keep_every_table_and_readers_see_whole_states() {
    let d = TempDir::new("concurrent-adds");
    let p = d.join("db.btdb");
    // Half the writers go through a symbolic link on Unix; elsewhere all through the name.
    #[cfg(unix)]
    let link = {
        let link = d.join("link.btdb");
        std::os::unix::fs::symlink("db.btdb", &link).unwrap();
        link
    };
    #[cfg(not(unix))]
    let link = p.clone();
    add(&p, "base", 0);
    let base = Store::open(&p).unwrap().table("base").unwrap().read_all();
    let base = base.unwrap();
    let done = AtomicBool::new(false);
    std::thread::scope(|s| {
        // Two writers through the file's name, two through the link.
        let writers: Vec<_> = (0..4)
            .map(|w| {
                let target = if w % 2 == 0 { &p } else { &link };
                s.spawn(move || {
                    for k in 0..5 {
                        add(target, &format!("w{w}k{k}"), 10 * w + k);
                    }
                })
            })
            .collect();
        // A reader: every state it opens is whole (verifies), holds `base` unchanged, and holds
        // at least the tables of the state before it.
        s.spawn(|| {
            let mut seen = 0;
            while !done.load(Ordering::Relaxed) {
                let st = Store::open(&p).expect("the database always opens");
                st.verify().expect("every state verifies");
                assert_eq!(st.table("base").unwrap().read_all().unwrap(), base);
                assert!(st.tables().len() >= seen, "a table vanished");
                seen = st.tables().len();
                // Wine keeps a file in use for milliseconds after its handle is closed, and
                // refuses to rename over it meanwhile: a reader opening it back to back kept
                // every writer out for the 2 s they retry (session 44, a loop of reads and
                // renames: 1 ms between reads, a rename refused 432 times in a row; 5 ms, at
                // most 3). How long Windows itself keeps a closed file in use was not measured.
                #[cfg(windows)]
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
        });
        // The reader stops before a failed writer's panic is raised: a writer that failed
        // (under Wine, "Access denied" while the reader held the file mapped) left the test
        // waiting for the reader for ever instead of failing it.
        let joined: Vec<_> = writers.into_iter().map(|w| w.join()).collect();
        done.store(true, Ordering::Relaxed);
        for r in joined {
            if let Err(panic) = r {
                std::panic::resume_unwind(panic);
            }
        }
    });
    let mut got = names(&p);
    got.sort();
    let mut want: Vec<String> = (0..4)
        .flat_map(|w| (0..5).map(move |k| format!("w{w}k{k}")))
        .chain(["base".to_owned()])
        .collect();
    want.sort();
    assert_eq!(got, want, "every writer's tables, none lost");
    #[cfg(unix)]
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink(),
        "the link is still a link (the writes went to the database it names)"
    );
    assert_eq!(names(&link).len(), want.len());
    // The tables hold what their writers wrote (to f16 precision).
    let st = Store::open(&p).unwrap();
    let got = st.table("w3k4").unwrap().read_all().unwrap();
    let worst = got
        .iter()
        .zip(values(34))
        .map(|(a, b)| ((a - b) / b).abs())
        .fold(0f32, f32::max);
    assert!(worst < 1e-3, "w3k4 read back {worst} off");
}

#[cfg(unix)]
#[test]
fn a_removal_through_a_link_removes_from_the_database() {
    let d = TempDir::new("remove-link");
    let p = d.join("db.btdb");
    add(&p, "a", 1);
    add(&p, "b", 2);
    let link = d.join("link.btdb");
    std::os::unix::fs::symlink(&p, &link).unwrap();
    db::remove(&link, "a").unwrap();
    assert_eq!(names(&p), ["b"]);
    let e = db::remove(&link, "a").unwrap_err().to_string();
    assert!(
        e.contains("link.btdb"),
        "the error names the user's path: {e}"
    );
}

#[test]
fn one_table_evaluated_and_sampled_from_many_threads_as_from_one() {
    let d = TempDir::new("threads-one-table");
    let dbp = d.join("m.btdb");
    let dbs = dbp.to_str().unwrap();
    let spec = r#"{"model": "ggx", "alpha": 0.3}"#;
    brdftab::BakeRequest::new(spec)
        .preset(brdftab::Preset::Small)
        .run(&brdftab::BakeTarget::db(dbs, "ggx"))
        .unwrap();
    let source = format!("{dbs}#ggx");
    // Lazily opened: chunks are decoded by whichever thread's lookup first needs them.
    let lazy = brdftab::open_with(&source, &brdftab::OpenOptions::default()).unwrap();
    let eager = brdftab::open_with(
        &source,
        &brdftab::OpenOptions {
            eager: true,
            ..Default::default()
        },
    )
    .unwrap();
    let mut rng = Pcg32::new(7);
    let mut dir = || {
        let (a, b) = (rng.next_f64(), rng.next_f64());
        DVec3::new(a - 0.5, b - 0.5, 0.2 + rng.next_f64())
    };
    let n = 2000;
    let wi: Vec<DVec3> = (0..n).map(|_| dir()).collect();
    let wo: Vec<DVec3> = (0..n).map(|_| dir()).collect();
    let u: Vec<DVec2> = (0..n)
        .map(|k| {
            DVec2::new(
                (k as f64 + 0.5) / n as f64,
                ((k * 7919) % n) as f64 / n as f64,
            )
        })
        .collect();
    let run = |b: &dyn Brdf| {
        let mut f = vec![0f32; 3 * n];
        let mut pdf = vec![0f64; n];
        let mut draws = Vec::with_capacity(n);
        let mut weight = [0f32; 3];
        for k in 0..n {
            b.eval(wi[k], wo[k], &mut f[3 * k..3 * k + 3]);
            pdf[k] = b.pdf(wi[k], wo[k]);
            let s = b.sample(wo[k], u[k], &mut weight);
            draws.push(s.map(|s| (s.wi, s.pdf, weight)));
        }
        (f, pdf, draws)
    };
    let want = run(eager.as_ref());
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..8).map(|_| s.spawn(|| run(lazy.as_ref()))).collect();
        for h in handles {
            let got = h.join().unwrap();
            assert!(got.0 == want.0, "f_r differs between threads");
            assert!(got.1 == want.1, "pdf differs between threads");
            assert!(got.2 == want.2, "samples differ between threads");
        }
    });
    lazy.health().unwrap();
    assert!(want.0.iter().any(|&v| v > 0.0), "the pairs see the lobe");
}
