"""flowplan's planning math as TorchScript source: the files flowplan compiles
into every planner it builds and exports (jit/library.h), one module per file,
a subpackage per folder of the repository (flowplan.script.geometry.box is
geometry/box.py).

Function modules hold free functions; class modules hold one class whose
methods flowplan compiles onto a TorchScript module it fills with buffers,
attributes and submodules. Called from Python, a class's methods take such a
module as `self`: ``Arm.tcp(planner.module.robot, q)`` runs the source of
kinematics/arm.py eagerly on the weights of an exported planner, as
``planner.module.robot.tcp(q)`` runs its compiled copy.
"""
