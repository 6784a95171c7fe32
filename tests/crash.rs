//! Crash safety: a writer process killed (SIGKILL) at any moment leaves the old database or the
//! new one — never a broken file, never a lost entry.
//!
//! The test re-invokes its own binary as the child (`crash_child`, ignored in a normal run),
//! which adds tables to a database in a loop, slowly, until killed.

use std::path::Path;
use std::time::Duration;

use brdftab::Channels;
use brdftab::codec::{Codec, Quant};
use brdftab::store::{Source, Store, TableHeader, db};

fn header(name: &str) -> TableHeader {
    TableHeader::new(
        name,
        Source::Other {
            description: "crash test".into(),
        },
        vec![8, 16, 32, 3],
        Channels::Rgb,
        Codec {
            quant: Quant::F16,
            level: 1,
            ..Codec::default()
        },
    )
}

fn add(path: &Path, name: &str, slow: bool) {
    let data: Vec<f32> = (0..8 * 16 * 32 * 3)
        .map(|i| ((i % 97) as f32 * 0.37).sin().abs())
        .collect();
    db::put(path, header(name), false, |w| {
        for c in data.chunks(16 * 32 * 3) {
            if slow {
                std::thread::sleep(Duration::from_millis(2));
            }
            w.chunk(c)?;
        }
        Ok(())
    })
    .unwrap();
}

fn names(path: &Path) -> Vec<String> {
    let s = Store::open(path).expect("database must always open");
    s.verify().expect("database must always verify");
    s.tables().iter().map(|t| t.name.clone()).collect()
}

/// The child (run by the test below with `--ignored`): adds tables `t<N>` until killed.
#[test]
#[ignore = "a child process of killed_writer_leaves_old_or_new_database"]
fn crash_child() {
    let p =
        std::env::var_os("BRDFTAB_CRASH_CHILD").expect("BRDFTAB_CRASH_CHILD names the database");
    let p = std::path::PathBuf::from(p);
    loop {
        let n = names(&p).len();
        add(&p, &format!("t{n}"), true);
    }
}

#[test]
fn killed_writer_leaves_old_or_new_database() {
    let dir = brdftab::testkit::TempDir::new("crash");
    let p = dir.join("db.btdb");
    add(&p, "t0", false);
    let exe = std::env::current_exe().unwrap();
    let mut kills = 0;
    for ms in [3u64, 11, 19, 27, 41, 60, 87, 120, 160, 230] {
        let before = names(&p);
        let mut child = std::process::Command::new(&exe)
            .args([
                "crash_child",
                "--exact",
                "--ignored",
                "--nocapture",
                "--test-threads=1",
            ])
            .env("BRDFTAB_CRASH_CHILD", &p)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(ms));
        child.kill().unwrap(); // SIGKILL on Unix
        child.wait().unwrap();
        kills += 1;
        let after = names(&p);
        assert!(
            after.len() >= before.len(),
            "lost entries: {before:?} -> {after:?}"
        );
        assert_eq!(&after[..before.len()], &before[..], "entries changed");
    }
    assert_eq!(kills, 10);
    // The database grew at least once (some writes completed between kills).
    assert!(names(&p).len() > 1);
}
