//! Collision resolution (El Topo §3.4, Los Topos Algorithm 1). Work in progress (issue 5).
