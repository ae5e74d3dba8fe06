"""Figures (matplotlib, Agg backend set here once; the house style applied by plotting.style).

style       HOUSE_STYLE, the `styled` decorator of every figure function, save_figure (atomic), figure_paths
paper       the paper's figures and Table 1
stability   the stability map
fields      field figures from the ParaView field files (read by data.fieldfiles)
ladder      the model ladder's figures
designs     the design studies' figures
"""
import matplotlib

matplotlib.use("Agg")   # figures go to files only

__all__ = ["designs", "fields", "ladder", "paper", "stability", "style"]
