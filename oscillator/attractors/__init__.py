"""Attractors: every attractor a case reaches from many starting states, its basin of attraction,
its Lyapunov exponents, and how the attractors change with a parameter (docs/attractors.md)."""
