//! Stage 5a (§8.1): one material label per grid vertex. Work in progress (issue 4).
