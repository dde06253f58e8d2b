"""Figures and animations of results: plots of columns against time, the mechanism moving."""

from .animate import ANIMATION_SUFFIXES, Scene, animate, html, movie_data
from .plots import PLOT_SUFFIXES, plot_columns, result_columns

__all__ = [
    "ANIMATION_SUFFIXES",
    "PLOT_SUFFIXES",
    "Scene",
    "animate",
    "html",
    "movie_data",
    "plot_columns",
    "result_columns",
]
