//! Swept-box and proximity broad phase. Work in progress (issue 5).
