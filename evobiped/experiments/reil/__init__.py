"""Reil & Husbands 2002: many evolutionary runs per condition and their statistics."""
