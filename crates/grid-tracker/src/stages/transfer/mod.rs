//! Stage 6 (§8.4): PIC transfer of vertex attributes. Work in progress (issue 4).
