// The extension module falling_mass_python: FallingMass in Python with one macro
// (saltus/python/bind_scene.hpp). `import falling_mass_python` imports saltus too.
#include "falling_mass.hpp"

#include <saltus/python/bind_scene.hpp>

PYBIND11_MODULE(falling_mass_python, m) {
  m.doc() = "A user's own scene, FallingMass, bound with SALTUS_PYTHON_BIND_SCENE";
  SALTUS_PYTHON_BIND_SCENE(m, FallingMass, "FallingMass");
}
