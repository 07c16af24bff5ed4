// libFuzzer target for the YAML readers: the first byte picks the reader (SPH, FEM and shell scenes, brush
// presets, paint types, palettes), the rest is its text. A reader refuses bad text with its own error
// (file:line:column); it must not crash, hang or allocate without bound.
#include <cstdint>
#include <exception>
#include <string>

#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/paint_palette.h"
#include "relaxed_connectivity/paint/paint_type_reader.h"
#include "relaxed_connectivity/shell/shell_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    switch (data[0] % 6) {
      case 0:
        (void)rc::parseSphScene(text, "fuzz.yaml");
        break;
      case 1:
        (void)rc::parseFemScene(text, "fuzz.yaml");
        break;
      case 2:
        (void)rc::parseShellScene(text, "fuzz.yaml");
        break;
      case 3:
        (void)rc::parseBrushPreset(text, "fuzz.yaml");
        break;
      case 4:
        (void)rc::parsePaintType(text, "fuzz.yaml");
        break;
      default:
        (void)rc::parsePalette(text, "fuzz.yaml");
        break;
    }
  } catch (const std::exception&) {
  }
  return 0;
}
