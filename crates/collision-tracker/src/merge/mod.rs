//! Snap merging (Los Topos §7.1). Work in progress (issue 5).
