//! The collision-safe edit guard (El Topo §3.5, Los Topos §5). Work in progress (issue 5).
