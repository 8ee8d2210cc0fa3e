// `anatomy-tutor figure-sheet`: rendered panels side by side with their captions under a title,
// one PNG per paper figure (render/figure_sheet.h; scripts/make_figures.sh calls it).
#include <cstdio>
#include <string>
#include <vector>

#include "cli_args.h"
#include "commands.h"
#include "render/figure_sheet.h"
#include "volume/png_image.h"
#include "printable_output.h"

namespace at::app {

namespace {

const char* const kUsage =
    "usage: anatomy-tutor figure-sheet --out SHEET.png [--title TEXT] [--columns N]\n"
    "                                  PANEL.png CAPTION [PANEL.png CAPTION ...]\n"
    "  Lays the panels side by side (N per row with --columns), each with its caption wrapped\n"
    "  underneath, under the title ('\\n' in a caption starts a line). Title and captions are UTF-8:\n"
    "  ASCII, Latin-1 letters and the common signs (µ ° ± × α β σ Δ ≤ ≥ → – — …) are drawn; any\n"
    "  other character as '?'.\n";

}  // namespace

int runFigureSheet(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"out", "title", "columns"}, {});
  if (!args) return reportError("figure-sheet: " + args.error().message, 2);
  if (args->has("help")) {
    terminalPrintf("%s", kUsage);
    return 0;
  }
  const auto out = args->value("out");
  if (!out) return reportError("figure-sheet: --out SHEET.png is required", 2);
  const auto& pos = args->positional();
  if (pos.empty() || pos.size() % 2 != 0)
    return reportError("figure-sheet: expected pairs of PANEL.png CAPTION (see --help)", 2);
  render::SheetLayout layout;
  auto columns = args->integer("columns", 0);
  if (!columns || *columns < 0) return reportError("figure-sheet: option --columns must be a whole number >= 0", 2);
  layout.columns = *columns;
  std::vector<render::SheetPanel> panels;
  for (std::size_t i = 0; i < pos.size(); i += 2) {
    auto image = readPng(pos[i]);
    if (!image) return reportError("figure-sheet: " + image.error().message);
    std::string caption;
    for (std::size_t k = 0; k < pos[i + 1].size(); ++k) {  // the shell passes "\n" as two characters
      if (pos[i + 1][k] == '\\' && k + 1 < pos[i + 1].size() && pos[i + 1][k + 1] == 'n') {
        caption += '\n';
        ++k;
      } else {
        caption += pos[i + 1][k];
      }
    }
    panels.push_back({std::move(*image), caption});
  }
  auto sheet = render::composeSheet(args->valueOr("title", ""), panels, layout);
  if (!sheet) return reportError(sheet.error().message);
  if (auto written = writePng(*out, *sheet); !written) return reportError("figure-sheet: " + written.error().message);
  terminalPrintf("wrote %s (%d panels, %dx%d)\n", out->c_str(), int(panels.size()), sheet->width, sheet->height);
  return 0;
}

}  // namespace at::app
