// A collision mesh (spheres::LoadMesh, then ValidateMesh): the first byte
// picks the format, OBJ (even) or STL (odd).

#include "fuzz/fuzz_input.h"
#include "spheres/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  try {
    const flowplan::spheres::Mesh mesh =
        flowplan::spheres::LoadMesh(flowplan::fuzz::AsFile(data + 1, size - 1, data[0] % 2 == 0 ? ".obj" : ".stl"));
    flowplan::spheres::ValidateMesh(mesh);
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
