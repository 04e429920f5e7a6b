"""The simulation options the Python tests share: the scene library's references::tight()
(relative 1e-12, absolute 1e-13), with which the C++ references they compare against are simulated."""
import saltus


def tight():
    o = saltus.SimulationOptions()
    o.relative_tolerance = 1e-12
    o.absolute_tolerance = 1e-13
    return o
