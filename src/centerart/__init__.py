"""centerart: joint shape reconstruction and 6-DoF grasp estimation of articulated objects from RGB-D.

Stages live in sub-packages (``assets``, ``grasps``, ``sdf``, ``models``, ``training``, ``scenes``,
``inference``, ``evaluation``, ``viz``); ``centerart --help`` lists the command of each.
"""

__version__ = "0.1.0"
