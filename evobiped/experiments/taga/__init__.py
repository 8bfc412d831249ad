"""Taga, Yamaguchi & Shimizu 1991: the Taga walker's experiments, stride metrics and figures."""
