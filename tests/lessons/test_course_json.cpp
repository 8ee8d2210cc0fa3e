#include <doctest/doctest.h>

#include <cmath>
#include <fstream>
#include <set>

#include "lessons/course_json.h"
#include "test_support.h"

using namespace at;
using namespace at::lessons;

namespace {

std::string minimalCourse(const std::string& lessons) {
  return R"({"schema": 1, "id": "c", "title": "C", "dataset": "phantom", "lessons": )" + lessons + "}";
}

const char* kShow = R"({"kind": "show", "structure": "cochlea", "preset": "cochlea_wdt", "view": "superior", "title": "T", "text": "X"})";

std::string errorOf(const std::string& text) {
  auto r = parseCourseJson(text, "bad.json");
  REQUIRE_FALSE(r);
  return r.error().message;
}

}  // namespace

TEST_CASE("ShippedCourse_ParsesWithFourLessonsEachWithShowStepsAndFiveMixedQuestions") {
  auto course = loadCourseJson(test::sourceDir() / "data/courses/temporal_bone.json");
  REQUIRE_MESSAGE(course, (course ? "" : course.error().message));
  CHECK(course->id == "temporal_bone");
  CHECK(course->datasetId == "phantom");
  REQUIRE(course->lessons.size() >= 4);
  std::set<quiz::QuestionKind> allKinds;
  for (const Lesson& lesson : course->lessons) {
    int shows = 0, questions = 0;
    std::set<quiz::QuestionKind> kinds;
    for (const Step& step : lesson.steps) {
      if (step.kind == StepKind::Show) {
        ++shows;
        CHECK_MESSAGE(step.show.text.size() > 150, lesson.id << ": show text too short for " << step.show.structure);
        const std::string& preset = step.show.presetId;
        CHECK((preset == step.show.structure + "_wdt" || preset == step.show.structure + "_bare"));
      }
      if (step.kind == StepKind::Question) {
        ++questions;
        kinds.insert(step.question.kind);
        allKinds.insert(step.question.kind);
      }
    }
    CHECK_MESSAGE(shows >= 2, lesson.id);
    CHECK_MESSAGE(questions >= 5, lesson.id);
    CHECK_MESSAGE(kinds.size() >= 3, lesson.id);
  }
  CHECK(allKinds.size() == 5);
}

TEST_CASE("CourseJson_RoundTripsThroughCourseToJson") {
  auto course = loadCourseJson(test::sourceDir() / "data/courses/temporal_bone.json");
  REQUIRE(course);
  auto again = parseCourseJson(courseToJson(*course), "round-trip");
  REQUIRE_MESSAGE(again, (again ? "" : again.error().message));
  CHECK(courseToJson(*again) == courseToJson(*course));
  for (const Lesson& lesson : course->lessons) {
    for (const Step& step : lesson.steps) {
      if (step.kind != StepKind::Question) continue;
      auto q = parseQuestionJson(questionToJson(step.question), step.question.id);
      REQUIRE(q);
      CHECK(questionToJson(*q) == questionToJson(step.question));
    }
  }
}

TEST_CASE("CourseJson_BadInputsAreErrorsNamingTheField") {
  CHECK(errorOf("{").find("bad.json: line 1, column 2: not valid JSON") == 0);
  CHECK(errorOf("[1]") == "bad.json: the document: must be an object");
  CHECK(errorOf(R"({"schema": 2, "id": "c"})").find("schema: unsupported version 2") != std::string::npos);
  CHECK(errorOf(R"({"id": "c"})").find("schema: missing") != std::string::npos);
  CHECK(errorOf(minimalCourse("[]")).find("lessons: must be a non-empty array") != std::string::npos);
  CHECK(errorOf(R"({"schema": 1, "id": "c", "title": "C", "dataset": "phantom", "colour": 1, "lessons": []})") ==
        "bad.json: colour: unknown field");
  const std::string lesson = R"([{"id": "a", "title": "A", "steps": [)";
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "show", "structure": "cochlea", "preset": "p", "view": "sideways", "title": "T", "text": "X"}]}])"))
            .find("bad.json: lessons[0].steps[0].view: unknown view 'sideways'") != std::string::npos);
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "question", "question": {"id": "q", "kind": "pick", "prompt": "P", "target": "cochlea"}}]}])"))
            .find("lessons[0].steps[0].question.kind: unknown question kind 'pick'") != std::string::npos);
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "question", "question": {"id": "q", "kind": "name", "prompt": "P", "target": "cochlea", "tolerance_mm": 1}}]}])"))
            .find("question.tolerance_mm: only allowed for locate questions") != std::string::npos);
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "question", "question": {"id": "q", "kind": "relation", "prompt": "P", "target": "cochlea", "relation": {"from": "cochlea", "kind": "reachable", "candidates": ["a", "b"]}}}]}])"))
            .find("relation.threshold_mm: reachable needs a threshold > 0") != std::string::npos);
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "question", "question": {"id": "q", "kind": "order", "prompt": "P", "target": "cochlea", "order": {"entry_mm": [1, 2], "target_structure": "x"}}}]}])"))
            .find("order.entry_mm: must be [x, y, z]") != std::string::npos);
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "question", "question": {"id": "q", "kind": "order", "prompt": "P", "target": "cochlea", "order": {"entry_mm": [1, 2, 3], "entry_structure": "y", "target_structure": "x"}}}]}])"))
            .find("give exactly one of entry_mm and entry_structure") != std::string::npos);
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "question", "question": {"kind": "name", "prompt": "P", "target": "cochlea"}}]}])"))
            .find("question.id: missing") != std::string::npos);
  CHECK(errorOf(minimalCourse(R"([{"id": "a", "title": "A", "prerequisites": ["b"], "steps": [)" + std::string(kShow) + "]}]"))
            .find("prerequisites[0]: 'b' is not an earlier lesson") != std::string::npos);
  CHECK(errorOf(minimalCourse(R"([{"id": "a", "title": "A", "steps": [)" + std::string(kShow) + R"(]}, {"id": "a", "title": "B", "steps": [)" +
                              kShow + "]}]"))
            .find("duplicate lesson id 'a'") != std::string::npos);
  const std::string q = R"({"kind": "question", "question": {"id": "dup", "kind": "name", "prompt": "P", "target": "cochlea"}})";
  CHECK(errorOf(minimalCourse(lesson + q + "," + q + "]}]")).find("duplicate question id 'dup'") != std::string::npos);
}

TEST_CASE("LoadCourseJson_MissingFileIsAnErrorNamingIt") {
  test::TempDir dir;
  auto r = loadCourseJson(dir / "nope.json");
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("nope.json") != std::string::npos);
  std::ofstream(dir / "empty.json") << "";
  CHECK_FALSE(loadCourseJson(dir / "empty.json"));
}

TEST_CASE("CourseJson_NumberBeyondDoubleIsAnErrorNamingLineAndField") {
  // 1e309 overflows a double: nlohmann-json throws out_of_range from the parser, which the reader
  // once let escape (the CLI said "internal error" with no file or line).
  const std::string lesson = R"([{"id": "a", "title": "A", "steps": [{"kind": "question", "question": )";
  const std::string text =
      minimalCourse(lesson + "\n{\"id\": \"q\", \"kind\": \"name\", \"prompt\": \"P\", \"target\": \"cochlea\",\n"
                             "\"difficulty\": 1e309}}]}])");
  CHECK(errorOf(text) ==
        "bad.json: line 3, column 20, field 'lessons[0].steps[0].question.difficulty': number 1e309 is out of range "
        "(beyond ±1.8e308)");
  auto question = parseQuestionJson(R"({"id": "q", "kind": "name", "prompt": "P", "target": "t", "difficulty": -1e400})", "q.json");
  REQUIRE_FALSE(question);
  CHECK(question.error().message == "q.json: line 1, column 79, field 'difficulty': number -1e400 is out of range (beyond ±1.8e308)");
}

TEST_CASE("CourseJson_KeysWithControlCharactersAreQuotedPrintably") {
  const std::string error = errorOf("{\"schema\": 1, \"id\": \"c\", \"ti\\u001b[31mtle\\n\": 1}");
  CHECK(error == "bad.json: ti\\x1b[31mtle\\n: unknown field");
  CHECK(error.find('\x1b') == std::string::npos);
}

TEST_CASE("CourseJson_QuestionScenes_LocateNeedsANeighbourNotItsTarget") {
  const std::string lesson = R"([{"id": "a", "title": "A", "steps": [)";
  const std::string locate = R"("question": {"id": "q", "kind": "locate", "prompt": "Click the cochlea.", "target": "cochlea"}})";
  auto ok = parseCourseJson(minimalCourse(lesson + R"({"kind": "question", "structure": "vestibule", "view": "superior", )" +
                                          locate + "]}]"),
                            "c.json");
  REQUIRE_MESSAGE(ok, (ok ? "" : ok.error().message));
  const Step& step = ok->lessons[0].steps[0];
  REQUIRE(step.scene.has_value());
  CHECK(step.scene->structure == "vestibule");
  CHECK((step.scene->view == CameraView::Superior));
  CHECK(sceneFor(step).presetId == "vestibule_wdt");  // the default preset of the scene's structure
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "question", )" + locate + "]}]")) ==
        "bad.json: lessons[0].steps[0].structure: a locate question needs the structure whose view shows the region "
        "(a neighbour of 'cochlea'), with its view");
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "question", "structure": "cochlea", "view": "superior", )" + locate + "]}]"))
            .find("bad.json: lessons[0].steps[0].structure: a locate question must not select its target 'cochlea'") == 0);
  CHECK(errorOf(minimalCourse(lesson + R"({"kind": "question", "structure": "vestibule", "view": "above", )" + locate + "]}]"))
            .find("bad.json: lessons[0].steps[0].view: unknown view 'above'") == 0);
  // Identify and name questions default to their target, highlighted.
  auto name = parseCourseJson(minimalCourse(lesson + R"({"kind": "question", "question": {"id": "n", "kind": "name", "prompt": "P", "target": "stapes"}}]}])"),
                              "c.json");
  REQUIRE(name);
  CHECK_FALSE(name->lessons[0].steps[0].scene.has_value());
  CHECK(sceneFor(name->lessons[0].steps[0]).structure == "stapes");
  CHECK(sceneFor(name->lessons[0].steps[0]).presetId == "stapes_wdt");
}

TEST_CASE("CourseJson_StepCameraAndClip_ReadNormalisedRoundTripAndBadOnesNameTheField") {
  const std::string lesson = R"([{"id": "a", "title": "A", "steps": [)";
  const std::string show = R"({"kind": "show", "structure": "cochlea", "preset": "cochlea_wdt", "view": "superior", "title": "T", "text": "X", )";
  const std::string camera = R"("camera": {"target_mm": [1, 2, 3], "look": [0, 0, -2], "up": [0.5, -1, 0.2], "distance_mm": 40})";
  auto ok = parseCourseJson(minimalCourse(lesson + show + camera + R"(, "clip": [0, -2, 0, 5]},)" +
                                          R"({"kind": "question", "structure": "vestibule", "clip": [0, 0, 1, -1.5], )" +
                                          R"("question": {"id": "q", "kind": "locate", "prompt": "P", "target": "cochlea"}}]}])"),
                            "c.json");
  REQUIRE_MESSAGE(ok, (ok ? "" : ok.error().message));
  const Step& s = ok->lessons[0].steps[0];
  REQUIRE(s.show.camera.has_value());
  CHECK(s.show.camera->targetMm == at::Vec3{1, 2, 3});
  CHECK(s.show.camera->look == at::Vec3{0, 0, -1});  // normalised
  CHECK(s.show.camera->up[2] == doctest::Approx(0));  // made orthogonal to look
  CHECK(s.show.camera->up[0] == doctest::Approx(0.5 / std::sqrt(1.25)));
  CHECK(s.show.camera->distanceMm == 40);
  REQUIRE(s.show.clip.has_value());
  CHECK(s.show.clip->normal == at::Vec3{0, -1, 0});
  CHECK(s.show.clip->d == doctest::Approx(2.5));  // scaled with the normal
  const Step& q = ok->lessons[0].steps[1];
  REQUIRE(q.scene.has_value());
  CHECK_FALSE(q.scene->camera.has_value());
  REQUIRE(q.scene->clip.has_value());
  CHECK(sceneFor(q).clip == q.scene->clip);
  auto again = parseCourseJson(courseToJson(*ok), "round-trip");
  REQUIRE_MESSAGE(again, (again ? "" : again.error().message));
  CHECK(courseToJson(*again) == courseToJson(*ok));
  CHECK(again->lessons[0].steps[0].show.camera == s.show.camera);
  CHECK(again->lessons[0].steps[1].scene->clip == q.scene->clip);
  // A course without them (every course written before) has none.
  auto plain = parseCourseJson(minimalCourse(lesson + kShow + "]}]"), "c.json");
  REQUIRE(plain);
  CHECK_FALSE(plain->lessons[0].steps[0].show.camera.has_value());
  CHECK_FALSE(plain->lessons[0].steps[0].show.clip.has_value());

  const auto showWith = [&](const std::string& extra) { return errorOf(minimalCourse(lesson + show + extra + "}]}]")); };
  CHECK(showWith(R"("clip": [1, 1, 0, 3])") ==
        "bad.json: lessons[0].steps[0].clip: the normal must lie along one patient axis (x, y or z), as the desktop's clip control offers");
  CHECK(showWith(R"("clip": [0, 0, 0, 3])") == "bad.json: lessons[0].steps[0].clip: the normal must not be zero");
  CHECK(showWith(R"("clip": [0, 0, 1])").find("bad.json: lessons[0].steps[0].clip: must be [nx, ny, nz, d]") == 0);
  CHECK(showWith(R"("camera": {"target_mm": [0, 0, 0], "up": [0, 0, 1], "distance_mm": 4})") ==
        "bad.json: lessons[0].steps[0].camera.look: missing");
  CHECK(showWith(R"("camera": {"target_mm": [0, 0, 0], "look": [0, 0, 1], "up": [0, 0, 3], "distance_mm": 4})") ==
        "bad.json: lessons[0].steps[0].camera.up: must not be zero or along 'look'");
  CHECK(showWith(R"("camera": {"target_mm": [0, 0], "look": [0, 0, 1], "up": [0, 1, 0], "distance_mm": 4})") ==
        "bad.json: lessons[0].steps[0].camera.target_mm: must be [x, y, z] in millimetres");
  CHECK(showWith(R"("camera": {"target_mm": [0, 0, 0], "look": [0, 0, 1], "up": [0, 1, 0], "distance_mm": 0})")
            .find("bad.json: lessons[0].steps[0].camera.distance_mm: must be a distance in millimetres above 0") == 0);
  CHECK(showWith(R"("camera": {"target_mm": [0, 0, 0], "look": [0, 0, 1], "up": [0, 1, 0], "distance_mm": 4, "roll": 1})") ==
        "bad.json: lessons[0].steps[0].camera.roll: unknown field");
}
