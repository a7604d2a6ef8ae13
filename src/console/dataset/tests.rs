//! The console's dataset jobs on simulated folders: a first session with 5
//! scans per texture trains and evaluates a sound model and says why k or
//! the split is not the profile's; stale and mismatched models are flagged.

use std::time::{Duration, Instant};

use super::*;
use crate::console::fixtures;
use crate::console::panels::{Panel, render_panel};

#[test]
fn counts_label_folders_and_unsaved_scans() {
    let d = tempfile::tempdir().unwrap();
    for (label, n) in [("S2", 3), ("S1", 2)] {
        std::fs::create_dir_all(d.path().join(label)).unwrap();
        for i in 0..n {
            std::fs::write(d.path().join(label).join(format!("{label}_{i}.csv")), "").unwrap();
        }
    }
    std::fs::create_dir_all(d.path().join(UNSAVED_DIR)).unwrap();
    std::fs::write(d.path().join(UNSAVED_DIR).join("scan-001.csv"), "").unwrap();
    let (counts, unsaved) = count(d.path());
    assert_eq!(counts, vec![("S1".into(), 2), ("S2".into(), 3)]);
    assert_eq!(unsaved, 1);
    assert_eq!(count(&d.path().join("missing")), (vec![], 0));
}

/// `per_class` simulated scans of every texture of the thesis profile.
fn simulated(per_class: usize) -> (tempfile::TempDir, LoadedProfile) {
    let d = tempfile::tempdir().unwrap();
    let lp = LoadedProfile::thesis();
    let opts = crate::acquire::SimulateOptions {
        out: d.path().to_path_buf(),
        per_class,
        seed: 7,
        threads: 2,
        gzip: false,
        overwrite: false,
    };
    crate::acquire::simulate_dataset(&lp, &opts, &|_, _| {}).unwrap();
    (d, lp)
}

/// The next job result, waiting up to a minute (the machine may be busy).
fn next_result(jobs: &Jobs) -> JobResult {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        if let Some(r) = jobs.poll().into_iter().next() {
            return r;
        }
        assert!(Instant::now() < deadline, "no job result within 60 s");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn text(buf: &ratatui::buffer::Buffer) -> String {
    let a = buf.area;
    let mut out = String::new();
    for y in a.y..a.bottom() {
        for x in a.x..a.right() {
            out.push_str(buf[(x, y)].symbol());
        }
        out.push('\n');
    }
    out
}

fn dataset_panel(app: &App) -> String {
    let area = ratatui::layout::Rect::new(0, 0, 110, 16);
    let mut buf = ratatui::buffer::Buffer::empty(area);
    render_panel(Panel::Dataset, app, area, &mut buf);
    text(&buf)
}

#[test]
fn a_first_session_of_five_scans_per_texture_trains_and_evaluates_a_sound_model() {
    let (d, lp) = simulated(5);
    let mut app = fixtures::app(120, 40);
    app.model = None;
    app.dataset = DatasetView {
        dir: d.path().to_path_buf(),
        ..DatasetView::default()
    };
    app.dataset.counts = count(d.path()).0;
    let jobs = Jobs::default();

    // e: the holdout split needs 30 per texture; it cross-validates instead.
    jobs.evaluate(&lp, d.path());
    let r = next_result(&jobs);
    let JobResult::Evaluated(e) = &r else {
        panic!("{r:?}");
    };
    let (report, method, note) = (&e.report, &e.method, &e.note);
    // The report kept beside the model: text and JSON, with the method
    // and k, and the same numbers as `hapticlab evaluate DIR --fallback`.
    let saved = e.saved.as_ref().unwrap();
    assert_eq!(saved, &d.path().join(super::REPORT_FILE));
    let text = std::fs::read_to_string(saved).unwrap();
    assert!(text.contains("5-fold cross-validation, seed 0"), "{text}");
    assert!(
        text.contains("fallback: the holdout split needs 30"),
        "{text}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.path().join(super::REPORT_JSON)).unwrap())
            .unwrap();
    assert_eq!(json["method"], "5-fold cross-validation, seed 0");
    assert_eq!(json["dataset"]["recordings"], 20);
    assert!(
        json["k_used"].as_array().is_some_and(|k| !k.is_empty()),
        "{json}"
    );
    assert!(report.accuracy >= 0.9, "accuracy {}", report.accuracy);
    assert_eq!(method, "5-fold cross-validation, seed 0");
    assert!(
        note.starts_with(
            "the holdout split needs 30 scans per texture (20 to train, 10 to test), S1 has 5: \
             evaluating by stratified 5-fold cross-validation instead; \
             k = 10 needs at least 10 scans per texture, S1 has 4 in a training part"
        ),
        "{note}"
    );
    app.on_job(r);
    assert!(
        app.status.text.starts_with("evaluated: 20/20 right (100.0 %) by 5-fold cross-validation, seed 0; the holdout split needs 30"),
        "{}",
        app.status.text
    );
    assert!(
        app.status
            .text
            .contains("by 5-fold cross-validation, seed 0; "),
        "{}",
        app.status.text
    );
    assert!(
        dataset_panel(&app).contains(
            "evaluation: 20/20 right (100.0 %) by 5-fold cross-validation, seed 0, in evaluation.txt"
        ),
        "{}",
        dataset_panel(&app)
    );
    // The next session opening the folder shows that evaluation again,
    // read from evaluation.json, with its age.
    let mut next = fixtures::app(120, 40);
    next.dataset = DatasetView {
        dir: d.path().to_path_buf(),
        ..DatasetView::default()
    };
    adopt_saved_model(&mut next, d.path());
    let kept = next.dataset.report.as_ref().expect("the kept evaluation");
    assert_eq!(kept, app.dataset.report.as_ref().unwrap());
    assert!(
        dataset_panel(&next).contains(
            "evaluation: 20/20 right (100.0 %) by 5-fold cross-validation, seed 0, just now, in evaluation.txt"
        ),
        "{}",
        dataset_panel(&next)
    );

    // T: k = 10 cannot be met by 5 per texture; the status line says so.
    jobs.train(&lp, d.path(), false);
    let r = next_result(&jobs);
    app.on_job(r);
    assert!(
        app.status
            .text
            .starts_with("k = 10 needs at least 10 scans per texture, S1 has 5: using k = "),
        "{}",
        app.status.text
    );
    assert!(
        app.status.text.contains("trained k-NN"),
        "{}",
        app.status.text
    );
    let panel = dataset_panel(&app);
    assert!(
        panel.contains("on 20 recordings of S1, S2, S3, S4"),
        "{panel}"
    );
    assert!(panel.contains("k = 10 needs at least 10 scans"), "{panel}");

    // The replay browser predicts each stored scan left out of the model.
    let files = recording::collect_files(&[d.path().to_path_buf()]).unwrap();
    app.replay = Some(crate::console::replay::Replay::new(
        d.path().to_path_buf(),
        files.clone(),
    ));
    jobs.list(&lp, files, app.model.clone(), None);
    let r = next_result(&jobs);
    app.on_job(r);
    let (right, n) = app.replay.as_ref().unwrap().score();
    assert_eq!(n, 20);
    assert!(right >= 18, "{right} of {n} right");
    assert!(
        app.status
            .text
            .starts_with("k = 10 needs at least 10 scans per texture")
            && app.status.text.contains("of 20 recordings predicted right"),
        "{}",
        app.status.text
    );
}

#[test]
fn a_stale_model_is_flagged_where_it_is_shown() {
    let mut app = fixtures::app(120, 40);
    // The fixture's model was trained on all 121 recordings: not stale.
    assert_eq!(app.dataset.stale_model(), None);
    assert!(dataset_panel(&app).contains("model: k-NN k = 10 on 121 recordings of S1"));
    app.dataset.counts[0].1 += 1;
    assert!(
        dataset_panel(&app).contains(
            "model stale: T trains again (k = 10, trained on 121 recordings, the dataset has 122)"
        ),
        "{}",
        dataset_panel(&app)
    );
    // Incomplete recordings that training skipped do not make it stale.
    app.dataset.model.as_mut().unwrap().skipped = 1;
    assert_eq!(app.dataset.stale_model(), None);
    // A curating change does, even with the counts unchanged.
    app.dataset.edits = 1;
    assert_eq!(
        app.dataset.stale_model().as_deref(),
        Some("trained before 1 change to the dataset")
    );
}

#[test]
fn a_saved_model_with_other_classifier_settings_is_not_used_silently() {
    let (d, lp) = simulated(3);
    let (examples, _) = load_examples(d.path(), &lp.profile.analysis).unwrap();
    let model = Model::train_adapting_k(
        &lp.profile.name,
        &lp.profile.analysis,
        &lp.profile.classifier,
        examples,
    )
    .unwrap();
    model
        .save(&d.path().join(MODEL_FILE), &[], crate::io::Existing::Keep)
        .unwrap();

    // Under the profile it was trained with, it is taken up.
    let mut app = fixtures::app(120, 40);
    app.model = None;
    app.dataset.model = None;
    adopt_saved_model(&mut app, d.path());
    assert!(app.model.is_some());
    assert_eq!(app.dataset.model.as_ref().unwrap().examples, 12);
    assert_eq!(app.dataset.model_note, None);
    app.dataset.counts = count(d.path()).0;
    assert_eq!(app.dataset.stale_model(), None);

    // Curated after it was saved (by an earlier session, or by hand), with
    // the count unchanged: one excluded, one added. The next session says
    // the model is stale, not "k-NN on 12 recordings".
    let s1 = d.path().join("S1");
    let excluded = d
        .path()
        .join(crate::console::curate::EXCLUDED_DIR)
        .join("S1");
    std::fs::create_dir_all(&excluded).unwrap();
    std::fs::rename(s1.join("S1_001.csv"), excluded.join("S1_001.csv")).unwrap();
    let mut app = fixtures::app(120, 40);
    adopt_saved_model(&mut app, d.path());
    app.dataset.counts = count(d.path()).0;
    assert_eq!(
        app.dataset.stale_model().as_deref(),
        Some("1 recording gone since it was trained")
    );
    std::fs::copy(s1.join("S1_002.csv"), s1.join("S1_009.csv")).unwrap();
    let mut app = fixtures::app(120, 40);
    adopt_saved_model(&mut app, d.path());
    app.dataset.counts = count(d.path()).0;
    assert_eq!(app.dataset.counts[0], ("S1".into(), 3));
    assert!(
        dataset_panel(&app).contains(
            "model stale: T trains again (k = 1, 1 recording added, 1 gone since it was trained)"
        ),
        "{}",
        dataset_panel(&app)
    );

    // Under a profile with k = 3 it is not, and both places say why.
    let mut app = fixtures::app(120, 40);
    app.model = None;
    app.dataset.model = None;
    app.profile.profile.classifier.k = 3;
    adopt_saved_model(&mut app, d.path());
    assert!(app.model.is_none());
    assert!(
        app.status.text.contains(
            "model.json not used: the model was trained with classifier.k = 10 but the profile \
             has classifier.k = 3"
        ),
        "{}",
        app.status.text
    );
    assert!(
        app.status.text.ends_with("(T trains a new one)"),
        "{}",
        app.status.text
    );
    assert_eq!(
        app.dataset.model_note.as_deref(),
        Some(app.status.text.as_str())
    );
    assert!(dataset_panel(&app).contains("model.json not used"));
}

/// Training and evaluating run nicer than the servo: a job's thread, and
/// the threads it starts, have a higher nice value than the console's.
#[cfg(target_os = "linux")]
#[test]
fn jobs_run_at_a_lower_priority_than_the_console() {
    fn nice() -> i32 {
        // SAFETY: reading the calling thread's own priority.
        unsafe {
            let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
            libc::getpriority(libc::PRIO_PROCESS, tid)
        }
    }
    let before = nice();
    let (job, inner) = std::thread::spawn(|| {
        super::lower_priority();
        let inner = std::thread::spawn(nice).join().unwrap();
        (nice(), inner)
    })
    .join()
    .unwrap();
    assert_eq!(nice(), before, "the calling thread is untouched");
    assert_eq!(job, (before + super::JOB_NICENESS).min(19));
    assert_eq!(inner, job, "threads a job starts inherit its priority");
}

/// A kept evaluation that does not hold together (5 labels, a 2x2 matrix)
/// is ignored with a word, never a panic; a FIFO there is never waited on.
#[test]
fn a_kept_report_that_does_not_hold_together_is_ignored_with_a_word() {
    let d = tempfile::tempdir().unwrap();
    let json = serde_json::json!({
        "labels": ["a", "b", "c", "d", "e"],
        "confusion": [[1, 0], [0, 1]],
        "accuracy": 1.0,
        "per_class": [],
        "method": "holdout",
    });
    std::fs::write(d.path().join(REPORT_JSON), json.to_string()).unwrap();
    let e = load_saved_report(d.path()).unwrap_err();
    assert!(
        e.contains("2x2 for 5 labels") && e.contains("ignored"),
        "{e}"
    );
    std::fs::remove_file(d.path().join(REPORT_JSON)).unwrap();
    let c = std::ffi::CString::new(d.path().join(REPORT_JSON).to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let e = load_saved_report(d.path()).unwrap_err();
    assert!(e.contains("FIFO"), "{e}");
    std::fs::remove_file(d.path().join(REPORT_JSON)).unwrap();
    assert!(load_saved_report(d.path()).unwrap().is_none());
}
