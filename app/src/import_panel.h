// The desktop app's import window (issue 7, "Long work and failures"): a form for a volume, an
// optional label map and names JSON, a dataset name and species; "Import" runs importDataset
// (dataset_import.h, the same function as `anatomy-tutor import`) on a background thread while
// the window shows its stage and progress, and "Cancel" stops it (a cancelled import stores
// nothing). A file that does not load shows the loader's one-line message; the app keeps running.
// After a successful import, "Open in explore view" hands the loaded dataset to the app.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "dataset_import.h"
#include "core/error.h"
#include "volume/structure.h"

namespace at::app {

class ImportPanel {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  using MessageSink = std::function<void(const std::string&)>;
  // `database`: where datasets are registered (the app's one connection; it outlives the panel).
  // `events` receives the scripted-mode events (import_progress, import_done, import_failed,
  // import_cancelled); `messages` the failures for the app's message list.
  ImportPanel(db::Database& database, EventSink events, MessageSink messages);
  // Cancels a running import and waits for its thread.
  ~ImportPanel();
  ImportPanel(const ImportPanel&) = delete;
  ImportPanel& operator=(const ImportPanel&) = delete;

  void open() { open_ = true; }
  bool running() const;

  // Every frame: reports the running import's progress and outcome (events, status line).
  void poll();
  // poll(), then the window at (x, y) when it is open.
  void draw(float x, float y);

  // Starts an import on the background thread; an error while another one runs.
  Status start(const ImportRequest& request);
  // Asks the running import to stop at its next check.
  void cancel();
  // The dataset of the last successful import once the user chose to open it (taken once).
  std::optional<Dataset> takeDatasetToOpen();

  // A scripted action: "import" (starts; with "wait": false it is done at once, otherwise when the
  // import ends; "cancel_at": a stage name cancels the import as that stage starts),
  // "cancel_import" (cancels and is done once the import has stopped), "open_imported". Returns
  // nullopt when `what` is not one of them, true when done, false while it runs, or an error.
  std::optional<Result<bool>> scriptAction(const std::string& what, const nlohmann::json& action);

 private:
  struct Job;
  Status launch(const ImportRequest& request, std::optional<ImportStage> cancelAt);
  void drawWindow(float x, float y);

  db::Database& database_;
  EventSink events_;
  MessageSink messages_;
  bool open_ = false;

  std::shared_ptr<Job> job_;      // the running or last import; shared with its thread
  std::jthread thread_;           // declared last: joined first on destruction
  bool reported_ = true;          // the job's outcome was reported
  std::string lastProgress_;      // last reported stage/progress (to report changes only)

  // Outcome shown in the window
  std::string status_;
  bool failed_ = false;
  std::optional<Dataset> imported_;  // ready to open in the explore view
  bool openRequested_ = false;
  bool scriptImporting_ = false;  // a scripted "import" waits for its outcome
  bool scriptOpening_ = false;    // a scripted "open_imported" waits for the app to take the dataset

  // Form
  char volume_[512] = "";
  char labels_[512] = "";
  char names_[512] = "";
  char name_[128] = "";
  char species_[64] = "human";
};

}  // namespace at::app
