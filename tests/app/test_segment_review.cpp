// The segment editor's review state per structure (not started, in progress, completed, flagged):
// set in the editor, saved with the structures into the dataset store, read back when the dataset
// is edited again; the UI-script action and its errors.
#include <doctest/doctest.h>

#include "db/connection.h"
#include "db/dataset_store.h"
#include "headless_desktop.h"
#include "segment_editor/segment_controller.h"
#include "test_support.h"

using namespace at;
using nlohmann::json;

namespace {

// A small imported dataset (its record only: the editor works on the Dataset given to attach)
// with two structures.
Dataset tinyDataset() {
  Geometry g;
  g.dims = {12, 10, 8};
  g.spacingMm = {0.5, 0.5, 1.5};
  Dataset ds;
  ds.id = "tiny";
  ds.volume = Volume(g, std::int16_t(0));
  ds.labels = LabelMap(g, 0);
  for (std::uint16_t label : {1, 2}) {
    Structure s;
    s.label = label;
    s.id = label == 1 ? "liver" : "spleen";
    s.displayName = label == 1 ? "Liver" : "Spleen";
    ds.structures.push_back(s);
    ds.labels.at(label * 3, 4, 4) = label;
  }
  return ds;
}

db::DatasetRecord recordOf(const Dataset& ds) {
  db::DatasetRecord r;
  r.name = ds.id;
  r.volumePath = "/data/tiny.nii.gz";
  r.volumeChecksum = "sha256:" + std::string(64, 'a');
  r.geometry = ds.volume.geometry;
  r.orientation = "LPS";
  return r;
}

}  // namespace

TEST_CASE("a structure's review state is set in the editor, stored with the structures, and read back") {
  test::TempDir dir;
  auto database = db::openDatabase((dir / "t.db").string());
  REQUIRE(database);
  const Dataset ds = tinyDataset();
  auto id = db::registerDataset(*database, recordOf(ds), ds.structures);
  REQUIRE(id);
  std::vector<json> events;
  {
    app::SegmentController editor(*database, [&](json e) { events.push_back(std::move(e)); });
    editor.attach(ds);
    CHECK(editor.reviewState(1) == db::ReviewState::NotStarted);
    REQUIRE(editor.setReviewState(1, db::ReviewState::Completed));
    REQUIRE(editor.setReviewState(2, db::ReviewState::InProgress));
    REQUIRE(editor.setReviewState(2, db::ReviewState::Flagged));
    CHECK(editor.reviewState(2) == db::ReviewState::Flagged);
    REQUIRE(events.size() == 3);
    CHECK(events.back() == json{{"event", "segment_review"}, {"structure", "spleen"}, {"state", "flagged"}});
    // The background and unknown labels have none.
    auto refused = editor.setReviewState(0, db::ReviewState::Completed);
    REQUIRE_FALSE(refused);
    CHECK(refused.error().message.find("no label 0") != std::string::npos);
    CHECK_FALSE(editor.setReviewState(9, db::ReviewState::Completed));
    // Not saved yet: the store still has them not started.
    auto stored = db::datasetReviewStates(*database, *id);
    REQUIRE(stored);
    CHECK(stored->at("spleen") == db::ReviewState::NotStarted);
    auto saved = editor.saveToStore();
    REQUIRE_MESSAGE(saved, test::errorText(saved));
  }
  auto stored = db::datasetReviewStates(*database, *id);
  REQUIRE(stored);
  CHECK(*stored == db::ReviewStates{{"liver", db::ReviewState::Completed}, {"spleen", db::ReviewState::Flagged}});
  // Edited again (another session): the editor starts from the stored states.
  app::SegmentController again(*database, [](json) {});
  again.attach(ds);
  CHECK(again.reviewState(1) == db::ReviewState::Completed);
  CHECK(again.reviewState(2) == db::ReviewState::Flagged);
  // A dataset that is not imported starts every structure not started.
  Dataset other = ds;
  other.id = "phantom";
  again.attach(other);
  CHECK(again.reviewState(1) == db::ReviewState::NotStarted);
}

TEST_CASE("UI script: segment_review sets a structure's state; a bad state or name ends the script with one message") {
  test::TempDir dir;
  test::HeadlessOptions options;
  options.dataset = "phantom:64";
  options.db = dir / "t.db";
  json actions = json::array({
      {{"do", "segment_open"}},
      {{"do", "segment_review"}, {"name", "cochlea"}, {"state", "in_progress"}},
      {{"do", "segment_review"}, {"name", "Cochlea"}, {"state", "completed"}},
  });
  auto run = test::runHeadless({{"actions", actions}}, options);
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);
  const auto review = test::eventsOf(run, "segment_review");
  REQUIRE(review.size() == 2);
  CHECK(review[1]["structure"] == "cochlea");
  CHECK(review[1]["state"] == "completed");

  run = test::runHeadless({{"actions", json::array({{{"do", "segment_review"}, {"name", "cochlea"}, {"state", "done"}}})}},
                          options);
  CHECK(run.exitCode == 2);
  CHECK(run.messages.find("must be not_started, in_progress, completed or flagged, not 'done'") != std::string::npos);
  run = test::runHeadless(
      {{"actions", json::array({{{"do", "segment_review"}, {"name", "background"}, {"state", "flagged"}}})}}, options);
  CHECK(run.exitCode == 2);
  CHECK(run.messages.find("a review state is for a structure") != std::string::npos);
}

TEST_CASE("the skull's structures open in the editor with the review states its shipped catalogue records") {
  // The built-in skull is not in the dataset store: its review (data/segmentations/skull/
  // structures.json) is what the editor shows until an instructor saves the labels as their own.
  test::TempDir dir;
  auto database = db::openDatabase((dir / "t.db").string());
  REQUIRE(database);
  Dataset ds = tinyDataset();
  ds.id = "skull";
  ds.structures[0].id = "mandible";
  ds.structures[1].id = "axis_c2";
  app::SegmentController editor(*database, [](json) {});
  editor.attach(ds);
  CHECK(editor.reviewState(1) == db::ReviewState::Completed);
  CHECK(editor.reviewState(2) == db::ReviewState::Flagged);
  // Any other dataset not in the store starts every structure as not started.
  ds.id = "tiny_unstored";
  editor.attach(ds);
  CHECK(editor.reviewState(1) == db::ReviewState::NotStarted);
  CHECK(editor.reviewState(2) == db::ReviewState::NotStarted);
}
