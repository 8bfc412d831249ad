"""Pribe, Grossberg & Cohen 1997: the G3 network under GO schedules, gait analysis and figures."""
