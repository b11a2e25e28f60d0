//! Stage 4 (§7, Appendix A): local mesh cutting. Work in progress (issue 4).
