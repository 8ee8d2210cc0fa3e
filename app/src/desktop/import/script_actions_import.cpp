// The UI script's import actions: the Import window's form, Cancel and Open buttons, through the
// ImportController.
#include "script/script_answers.h"
#include "script/script_interpreter.h"

namespace at::app {

using json = nlohmann::json;

ScriptInterpreter::Feature ScriptInterpreter::importActions() {
  using S = ScriptInterpreter;
  return {"import",
          "the Import window",
          {
              {"import",
               {{"volume", "the volume file or DICOM folder"}, {"name", "the dataset's name"}, {"labels?", "a label volume"},
                {"names?", "the labels' names (JSON)"}, {"species?", "default human"},
                {"intensity?", "auto (default), hu or plain"}, {"intercept?", "rescale: value x slope + intercept"},
                {"slope?", "rescale (default 1 with an intercept)"},
                {"modality?", "a DICOM modality (MR, PT, …) for a file that records none"},
                {"wait?", "true (default): done when the import ends; false: at once"},
                {"cancel_at?", "a stage name: cancel as that stage starts"}},
               "Starts an import as the Import window's form does.", &S::importDataset},
              {"cancel_import", {}, "Cancels the import; done once its outcome is out.", &S::cancelImport},
              {"open_imported", {}, "Opens the imported dataset; done once the app has taken it.", &S::openImported},
          }};
}

// Starts (with "wait": false done at once, else when the import ends; "cancel_at": a stage name
// cancels the import as that stage starts), shown as a user would see it: the window open on the
// form that started it.
ScriptInterpreter::Outcome ScriptInterpreter::importDataset(Context& c) {
  ImportController& im = c.model.imports();
  if (c.first) {
    ImportRequest request;
    request.volumePath = c.action.at("volume").get<std::string>();
    request.labelsPath = c.action.value("labels", "");
    request.namesPath = c.action.value("names", "");
    request.name = c.action.at("name").get<std::string>();
    request.species = c.action.value("species", "human");
    if (c.action.contains("intensity")) {
      auto choice = parseIntensityChoice(c.action.at("intensity").get<std::string>());
      if (!choice) return fail("ui script: import: \"intensity\": " + choice.error().message);
      request.intensity = *choice;
    }
    if (c.action.contains("intercept")) request.intercept = c.action.at("intercept").get<double>();
    if (c.action.contains("slope")) request.slope = c.action.at("slope").get<double>();
    request.modality = c.action.value("modality", "");
    std::optional<ImportStage> cancelAt;
    if (c.action.contains("cancel_at")) {
      cancelAt = parseImportStage(c.action.at("cancel_at").get<std::string>());
      if (!cancelAt) return fail("ui script: import: \"cancel_at\" must be one of " + importStageNames());
    }
    if (auto st = im.start(request, cancelAt); !st) return tl::unexpected(st.error());
    im.windowOpen = true;
    im.form = request;
    if (!c.action.value("wait", true)) return Progress::Done;
  }
  return im.reported() ? Progress::Done : Progress::Running;
}

// Cancels; done once the outcome (cancelled, or done if it was too late) is out.
ScriptInterpreter::Outcome ScriptInterpreter::cancelImport(Context& c) {
  c.model.imports().cancel();
  return c.model.imports().reported() ? Progress::Done : Progress::Running;
}

// Done once the app has taken the dataset (in its next frame).
ScriptInterpreter::Outcome ScriptInterpreter::openImported(Context& c) {
  ImportController& im = c.model.imports();
  if (c.first) {
    if (!im.canOpen()) return fail("ui script: open_imported: no successful import to open");
    im.requestOpen();
    return Progress::Running;
  }
  return im.openRequested() ? Progress::Running : Progress::Done;
}

}  // namespace at::app
