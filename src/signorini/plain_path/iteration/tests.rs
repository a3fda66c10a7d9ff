//! Unit tests of the plain path's Newton loop (iteration.rs).

use super::*;

const INEXACT: StepPlan = StepPlan {
    exact: false,
    predict: false,
    confirm: false,
    correct: false,
    loose: false,
};

#[test]
fn inexact_steps_run_while_the_set_shrinks_and_end_in_an_exact_repeat() {
    let mut last = usize::MAX;
    // changes 10, then 4: still loose
    assert_eq!(
        INEXACT.after_solve(false, 10, false, &mut last),
        After::Update(INEXACT)
    );
    assert_eq!(
        INEXACT.after_solve(false, 4, false, &mut last),
        After::Update(INEXACT)
    );
    // nothing changes: the same sets once more, exactly
    let exact = StepPlan {
        exact: true,
        ..INEXACT
    };
    assert_eq!(
        INEXACT.after_solve(false, 0, false, &mut last),
        After::Repeat(exact)
    );
    // a recurring set likewise
    assert_eq!(
        INEXACT.after_solve(false, 3, true, &mut last),
        After::Repeat(exact)
    );
    // exact stays exact
    assert_eq!(
        exact.after_solve(true, 5, false, &mut last),
        After::Update(exact)
    );
}

#[test]
fn a_loose_step_without_progress_makes_the_rest_exact() {
    let mut last = usize::MAX;
    assert_eq!(
        INEXACT.after_solve(false, 6, false, &mut last),
        After::Update(INEXACT)
    );
    let exact = StepPlan {
        exact: true,
        ..INEXACT
    };
    assert_eq!(
        INEXACT.after_solve(false, 6, false, &mut last),
        After::Update(exact)
    );
}

#[test]
fn the_prediction_decides_and_predicts_once() {
    let first = StepPlan {
        predict: true,
        ..INEXACT
    };
    let mut last = usize::MAX;
    // a set predicted inside the model: exact from here (the first step's solve loose),
    // no second prediction (the model corrects the updates instead)
    let exact = StepPlan {
        exact: true,
        correct: true,
        loose: true,
        ..INEXACT
    };
    assert_eq!(
        first.after_solve(true, 40, false, &mut last),
        After::Update(exact)
    );
    // truncated at the model's border: loose steps first
    assert_eq!(
        first.after_solve(false, 40, false, &mut last),
        After::Update(INEXACT)
    );
    // where every solve is exact (a factorisation), no step is loosened
    let first_exact = StepPlan {
        exact: true,
        ..first
    };
    assert_eq!(
        first_exact.after_solve(true, 40, false, &mut last),
        After::Update(StepPlan {
            loose: false,
            ..exact
        })
    );
}

/// The prediction's own step, solved inexactly or not at all (a floating body's skipped
/// first solve), is never the last one: where the model keeps its set, the same sets are
/// solved once more exactly (tests/predictor.rs, three blocks pressed by Dirichlet data).
#[test]
fn a_prediction_that_changes_nothing_after_an_inexact_solve_is_solved_again() {
    let first = StepPlan {
        predict: true,
        ..INEXACT
    };
    let mut last = usize::MAX;
    assert_eq!(
        first.after_solve(true, 0, false, &mut last),
        After::Repeat(StepPlan {
            exact: true,
            correct: true,
            ..INEXACT
        })
    );
    // after an exact solve (a factorisation) the update decides as ever
    let first_exact = StepPlan {
        exact: true,
        ..first
    };
    assert_eq!(
        first_exact.after_solve(true, 0, false, &mut last),
        After::Update(StepPlan {
            exact: true,
            correct: true,
            ..INEXACT
        })
    );
}

/// The first step from a predicted set is solved loosely; it is never the last one: where
/// it changes nothing (or its set recurs) the same sets are solved once more exactly, and
/// every step after it is exact.
#[test]
fn a_loose_first_step_from_a_prediction_is_followed_by_exact_ones() {
    let loose = StepPlan {
        exact: true,
        correct: true,
        loose: true,
        ..INEXACT
    };
    let exact = StepPlan {
        loose: false,
        ..loose
    };
    let mut last = usize::MAX;
    assert_eq!(
        loose.after_solve(true, 0, false, &mut last),
        After::Repeat(exact)
    );
    assert_eq!(
        loose.after_solve(true, 2, true, &mut last),
        After::Repeat(exact)
    );
    assert_eq!(
        loose.after_solve(true, 24, false, &mut last),
        After::Update(exact)
    );
    assert_eq!(
        exact.after_solve(true, 0, false, &mut last),
        After::Update(exact)
    );
}

#[test]
fn the_next_rows_hold_only_within_the_slack_of_the_own_rows_or_the_floor() {
    // the step testing |Δu| is skipped where the next rows hold at the iterate to round-off
    assert!(rows_hold((1e-18, 1e-17), 1e-22));
    assert!(rows_hold((0.0, 1e-21), 1e-22));
    assert!(!rows_hold((1e-18, 1e-15), 1e-22));
    assert!(!rows_hold((0.0, 1e-20), 1e-22));
}

#[test]
fn a_residual_is_round_off_only_when_still_steps_stop_reducing_it() {
    // two still steps, the residual not halved, small against ‖λ‖: round-off
    assert!(stalled(true, Some(9e-13), 8.9e-13, 6e-4, 0.0));
    // the first still step: no verdict yet
    assert!(!stalled(true, None, 8.9e-13, 6e-4, 0.0));
    // still decreasing: Newton is still working
    assert!(!stalled(true, Some(9e-12), 8.9e-13, 6e-4, 0.0));
    // states or u still move
    assert!(!stalled(false, Some(9e-13), 8.9e-13, 6e-4, 0.0));
    // stalled, but far from small: not a solution
    assert!(!stalled(true, Some(1e-3), 1e-3, 6e-4, 0.0));
    // ... unless c's rounding explains it: c = 1e12, ‖u‖₂ = 1 on the contact nodes
    let floor = residual_floor(1e12, 1.0);
    assert!(floor > 1e-3 && floor < 1e-2, "{floor:e}");
    assert!(stalled(true, Some(1e-3), 1e-3, 6e-4, floor));
    assert!(!stalled(true, Some(3e-3), 3e-3, 6e-4, floor));
}

#[test]
fn a_stop_on_a_reused_step_is_confirmed_once_by_a_factorisation() {
    let exact = StepPlan {
        exact: true,
        ..INEXACT
    };
    let confirm = StepPlan {
        confirm: true,
        ..exact
    };
    assert_eq!(exact.after_stop(true), After::Repeat(confirm));
    assert_eq!(exact.after_stop(false), After::Update(exact));
    assert_eq!(confirm.after_stop(true), After::Update(confirm));
    // every step after a confirming one is factorised
    let mut last = usize::MAX;
    assert_eq!(
        confirm.after_solve(true, 2, false, &mut last),
        After::Update(confirm)
    );
}

#[test]
fn the_model_corrects_the_exact_steps_from_a_predicted_set_on_only() {
    let predict = StepPlan {
        predict: true,
        ..INEXACT
    };
    let mut last = usize::MAX;
    // the prediction accepted (exact from then on): the next steps are corrected
    let After::Update(next) = predict.after_solve(true, 40, false, &mut last) else {
        panic!("a prediction is followed by an update");
    };
    assert!(next.correct && next.exact && !next.predict);
    let exact_corrected = StepPlan {
        loose: false,
        ..next
    };
    assert_eq!(
        next.after_solve(true, 3, false, &mut last),
        After::Update(exact_corrected)
    );
    // a prediction not accepted (inexact steps follow): no correction
    let After::Update(loose) = predict.after_solve(false, 40, false, &mut last) else {
        panic!("an inexact step that changes nodes is followed by an update");
    };
    assert!(!loose.correct);
    // without a prediction, nothing is corrected
    let exact = StepPlan {
        exact: true,
        ..INEXACT
    };
    let After::Update(e) = exact.after_solve(true, 3, false, &mut last) else {
        panic!("an exact step is followed by an update");
    };
    assert!(!e.correct);
}
