//! `seat_twin::gui::files_view`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::gui::files_view::*;

/// Nothing to lose: the action runs at once. Unsaved changes: it waits for the answer.
#[test]
fn guard_holds_an_action_only_over_unsaved_changes() {
    let mut v = FilesView::default();
    assert_eq!(
        v.guard(Pending::OpenDialog, false),
        Some(Pending::OpenDialog)
    );
    assert!(!v.is_confirm_open());
    assert_eq!(v.guard(Pending::OpenSessionDialog, true), None);
    assert!(v.is_confirm_open());
}

/// Closing with unsaved changes is held and asks; once quitting is confirmed the close
/// goes through. Without changes it is never held.
#[test]
fn close_is_held_until_quitting_is_confirmed() {
    let mut v = FilesView::default();
    assert!(!v.hold_close(false));
    assert!(!v.is_confirm_open());
    assert!(v.hold_close(true));
    assert!(v.is_confirm_open());
    v.confirm_quit();
    assert!(!v.hold_close(true));
}
