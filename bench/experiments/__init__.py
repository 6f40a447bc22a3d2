"""Experiments built on rigs and textures: Bayesian exploration for texture identification (D ch. 6) — pilot, training, validation and virtual exploration, pure functions over trial tables."""
