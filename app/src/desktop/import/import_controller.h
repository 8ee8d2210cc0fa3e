// The desktop's import without drawing (the Import window draws it; the UI script drives the same
// commands): importDataset (dataset_import.h, as `anatomy-tutor import`) runs on a background
// thread while poll() reports its stages and progress, Cancel stops it (a cancelled import stores
// nothing), a file that does not load gives the loader's one-line message, and after a successful
// import the loaded dataset can be opened in the explore view.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "dataset_import.h"
#include "volume/structure.h"

namespace at::app {

class ImportController {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  using MessageSink = std::function<void(const std::string&)>;
  // `database`: where datasets are registered (the app's one connection; it outlives the
  // controller). `events` receives import_started, import_progress, import_done, import_failed and
  // import_cancelled; `messages` the failures for the app's message list.
  ImportController(db::Database& database, EventSink events, MessageSink messages);
  // Cancels a running import and waits for its thread.
  ~ImportController();
  ImportController(const ImportController&) = delete;
  ImportController& operator=(const ImportController&) = delete;

  // The form the window shows (a scripted import fills it as a user would).
  ImportRequest form;
  bool windowOpen = false;

  // Starts importing `request` on the background thread (an error while another one runs).
  // `cancelAt`: cancel as that stage starts (scripts: deterministic cancellation).
  Status start(const ImportRequest& request, std::optional<ImportStage> cancelAt = std::nullopt);
  void cancel();  // asks the running import to stop at its next check
  bool running() const;
  // Each frame: reports the running import's stages and outcome (events, status line).
  void poll();
  // The running import's progress, for a bar.
  struct Progress {
    ImportStage stage = ImportStage::Checking;
    std::size_t done = 0, total = 0;
    bool cancelling = false;
    float fraction = 0;      // of the whole import, stages weighted by their usual share
    std::string text;        // "loading volume: slice 12 of 93"
  };
  std::optional<Progress> progress() const;
  // True once the outcome of the last import has been reported.
  bool reported() const { return reported_; }

  const std::string& status() const { return status_; }
  bool failed() const { return failed_; }
  bool canOpen() const { return imported_.has_value(); }
  // "Open in explore view": the imported dataset is handed over by takeDatasetToOpen() (once).
  void requestOpen() { openRequested_ = imported_.has_value(); }
  bool openRequested() const { return openRequested_; }
  std::optional<Dataset> takeDatasetToOpen();
  // The dataset handed over could not be shown: the Import window says why (in red) and the
  // explore view keeps what it showed [event import_open_failed].
  void openFailed(const std::string& why);

 private:
  struct Job;
  db::Database& database_;
  EventSink events_;
  MessageSink messages_;
  std::shared_ptr<Job> job_;      // the running or last import; shared with its thread
  std::jthread thread_;           // declared after job_: joined first on destruction
  bool reported_ = true;
  std::string lastProgress_;      // last reported stage/progress (to report changes only)
  std::string status_;
  bool failed_ = false;
  std::optional<Dataset> imported_;  // ready to open in the explore view
  bool openRequested_ = false;
};

// "checking", "loading volume", …: the stage called `name`, if any; and all names, for messages.
std::optional<ImportStage> parseImportStage(const std::string& name);
std::string importStageNames();

}  // namespace at::app
