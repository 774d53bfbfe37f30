"""See the robot and its runs: figures, visual geometry, headless 3-D animation, an interactive browser viewer (Thesis Annex A).

* :func:`plot_result`: any panels of a run (Chapter 6 figures, titled with the thesis's figure
  numbers of its scenario), on a page saved to a file, as a returned Figure or into your Axes
  (:mod:`qprr.viz.plots`); :func:`new_figure`, :func:`figure_path` for your own (matplotlib
  Figures, no pyplot, no backend chosen); :func:`fit_texts` re-wraps titles and labels that leave the page;

* :func:`animate` / :func:`animate_result`: a run (or an IK solution path, :func:`ik_path`) to
  GIF or MP4 with matplotlib, no display needed (:mod:`qprr.viz.animation`);
* :func:`visual_model`: the platform's visual ``GeometryModel`` (URDF shapes and meshes, or primitives);
* :class:`RunLog`, :func:`load_run`: a run as the viewers read it, from a result file (:meth:`qprr.sim.SimResult.save`);
* the browser viewer (``qprr view``, :class:`qprr.viz.viewer.Viewer`): joint sliders (FK), a
  draggable end-effector target solved by the task-priority IK, CoG and thrust-axis markers,
  hover thrusts and margins, a player for saved runs.  It needs the ``viewer`` extra
  (``pip install 'qprr[viewer]'``: viser); importing :mod:`qprr.viz.viewer` without it raises
  :class:`~qprr.errors.MissingDependencyError`.
"""

from .animation import AnimationInfo, AnimationOptions, animate, animate_result
from .geometry import primitive_visual_model, visual_model
from .ikpath import IKPath, ik_levels, ik_path, ik_solve
from .plots import PlotOptions, figure_path, fit_texts, new_figure, plot_result
from .run import RunLog, load_run
from .scene import HoverReport, RobotPose, hover_report, robot_pose

__all__ = [
    "AnimationInfo",
    "AnimationOptions",
    "HoverReport",
    "IKPath",
    "PlotOptions",
    "RobotPose",
    "RunLog",
    "animate",
    "animate_result",
    "figure_path",
    "fit_texts",
    "hover_report",
    "ik_levels",
    "ik_path",
    "ik_solve",
    "load_run",
    "new_figure",
    "plot_result",
    "primitive_visual_model",
    "robot_pose",
    "visual_model",
]
