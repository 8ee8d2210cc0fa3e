// The shipped course on the phantom: every structure id exists, every key computes, computed keys
// match hand-reasoned anatomy, and every lesson plays through the engine.
#include <doctest/doctest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

#include "course_wording.h"
#include "in_memory_repositories.h"
#include "lessons/course_json.h"
#include "lessons/exam.h"
#include "lessons/lesson_engine.h"
#include "test_support.h"
#include "volume/phantom.h"
#include "wdt/wdt.h"

using namespace at;
using namespace at::lessons;

namespace {

// The phantom at 128³ (0.4 mm voxels) with a WDT-backed key computer (CPU, default parameters),
// built once for all tests in this file.
struct PhantomKeys {
  Dataset dataset;
  std::unique_ptr<quiz::DatasetKeyComputer> keys;
  Course course;
};

PhantomKeys& phantomKeys() {
  static PhantomKeys p = [] {
    PhantomKeys k;
    PhantomOptions options;
    options.size = 128;
    k.dataset = makePhantom(options);
    const Dataset* dataset = &k.dataset;
    k.keys = std::make_unique<quiz::DatasetKeyComputer>(k.dataset, [dataset](const Mask& seeds) -> Result<FloatVolume> {
      WdtParams params;
      params.backend = WdtBackend::Cpu;
      auto r = computeWdt(dataset->volume, seeds, params);
      if (!r) return tl::unexpected(r.error());
      return std::move(r->field.distances);
    });
    auto course = loadCourseJson(test::sourceDir() / "data/courses/temporal_bone.json");
    REQUIRE_MESSAGE(course, (course ? "" : course.error().message));
    k.course = *course;
    return k;
  }();
  return p;
}

const quiz::Question& findQuestion(const Course& course, const std::string& id) {
  for (const Lesson& l : course.lessons)
    for (const Step& s : l.steps)
      if (s.kind == StepKind::Question && s.question.id == id) return s.question;
  FAIL("no question " << id);
  throw 0;
}

std::ptrdiff_t position(const std::vector<std::string>& v, const std::string& x) {
  const auto it = std::find(v.begin(), v.end(), x);
  return it == v.end() ? -1 : it - v.begin();
}

}  // namespace

TEST_CASE("ShippedCourses_StructureNamesInsideSentencesAreLowerCaseAndNoProgramJargon_PromptsExamsAndFeedback") {
  PhantomKeys& p = phantomKeys();
  CHECK(test::capitalisedMidSentence("Locate the Cochlea in the view.", p.dataset.structures) == std::vector<std::string>{"Cochlea"});
  CHECK(test::capitalisedMidSentence("Cochlea. The Vestibule: Incus", p.dataset.structures) == std::vector<std::string>{"Vestibule"});
  CHECK(test::jargonIn("The WDT from the seeds, on a preset.") == std::vector<std::string>{"wdt", "preset", "seeds"});
  CHECK(test::jargonIn("Enamel is above 1800 HU.") == std::vector<std::string>{"hu"});
  CHECK(test::jargonIn("Enamel is above 1800 Hounsfield units (HU); the hub of a shuttle.").empty());
  int courses = 0, texts = 0;
  for (const auto& entry : std::filesystem::directory_iterator(test::sourceDir() / "data/courses")) {
    if (entry.path().extension() != ".json") continue;
    auto course = loadCourseJson(entry.path());
    REQUIRE_MESSAGE(course, (course ? "" : course.error().message));
    CAPTURE(course->id);
    ++courses;
    // Courses on a scan (the skull CT) need the scan for their keys and names: tests/app's
    // test_skull_course checks them where the scan could be fetched. Here: the phantom's courses.
    if (course->datasetId != "phantom") {
      MESSAGE(entry.path().filename().string() << " is on dataset " << course->datasetId << ": not read here");
      continue;
    }
    texts += test::checkCourseWording(*course, p.dataset.structures, *p.keys);
  }
  CHECK(courses >= 1);
  MESSAGE(courses << " course(s), " << texts << " texts read");
}

TEST_CASE("ShippedCourse_EveryStructureExistsAndEveryQuestionKeyComputesOnThePhantom") {
  PhantomKeys& p = phantomKeys();
  for (const auto& [id, names] : p.course.synonyms) CHECK_MESSAGE(p.keys->hasStructure(id), "synonyms: " << id);
  for (const Lesson& lesson : p.course.lessons) {
    for (const Step& step : lesson.steps) {
      if (step.kind == StepKind::Show) {
        CHECK_MESSAGE(p.keys->hasStructure(step.show.structure), lesson.id << ": " << step.show.structure);
        continue;
      }
      auto r = quiz::resolveQuestion(step.question, *p.keys);
      REQUIRE_MESSAGE(r, (r ? "" : r.error().message));
      switch (step.question.kind) {
        case quiz::QuestionKind::Identify:
        case quiz::QuestionKind::Relation:
          CHECK(r->keyChoice >= 0);
          CHECK(r->keyChoice < int(r->choices.size()));
          break;
        case quiz::QuestionKind::Order:
          CHECK(r->keyOrder.size() >= 2);
          for (const std::string& id : r->keyOrder) CHECK(position(r->choices, id) >= 0);
          break;
        default: break;
      }
    }
  }
}

TEST_CASE("PhantomKeys_FromTheCochleaTheVestibuleIsNearerThanTheSigmoidSinusAndCarotid") {
  PhantomKeys& p = phantomKeys();
  auto d = p.keys->distancesFrom("cochlea");
  REQUIRE(d);
  CHECK((*d)["vestibule"] < (*d)["carotid_canal"]);
  CHECK((*d)["carotid_canal"] < (*d)["sigmoid_sinus"]);
  auto r = quiz::resolveQuestion(findQuestion(p.course, "inner_ear.cochlea_nearest"), *p.keys);
  REQUIRE(r);
  CHECK(r->choices[std::size_t(r->keyChoice)] == "vestibule");
}

TEST_CASE("PhantomKeys_ReachabilityFollowsFluidAndAirNotDenseBone") {
  PhantomKeys& p = phantomKeys();
  auto vestibule = quiz::resolveQuestion(findQuestion(p.course, "inner_ear.vestibule_reachable"), *p.keys);
  REQUIRE(vestibule);
  CHECK(vestibule->choices[std::size_t(vestibule->keyChoice)] == "posterior_semicircular_canal");
  auto cells = quiz::resolveQuestion(findQuestion(p.course, "mastoidectomy_landmarks.air_cells_reachable"), *p.keys);
  REQUIRE(cells);
  CHECK(cells->choices[std::size_t(cells->keyChoice)] == "tympanic_cavity");
  auto stapes = quiz::resolveQuestion(findQuestion(p.course, "middle_ear.stapes_nearest"), *p.keys);
  REQUIRE(stapes);
  CHECK(stapes->choices[std::size_t(stapes->keyChoice)] == "vestibule");
  auto nerve = quiz::resolveQuestion(findQuestion(p.course, "facial_nerve.nearest_canal"), *p.keys);
  REQUIRE(nerve);
  CHECK(nerve->choices[std::size_t(nerve->keyChoice)] == "lateral_semicircular_canal");
}

TEST_CASE("PhantomKeys_MastoidDrillPathMeetsAirCellsBeforeTheLateralCanal") {
  PhantomKeys& p = phantomKeys();
  auto r = quiz::resolveQuestion(findQuestion(p.course, "mastoidectomy_landmarks.order_drill_path"), *p.keys);
  REQUIRE(r);
  CHECK(r->keyOrder.front() == "mastoid_air_cells");
  CHECK(r->keyOrder.back() == "lateral_semicircular_canal");
  CHECK(position(r->keyOrder, "sigmoid_sinus") == -1);  // the path stays in front of the sinus
}

TEST_CASE("PhantomKeys_SoundPathAndFacialNervePathMeetStructuresInAnatomicalOrder") {
  PhantomKeys& p = phantomKeys();
  auto sound = quiz::resolveQuestion(findQuestion(p.course, "middle_ear.order_sound_path"), *p.keys);
  REQUIRE(sound);
  const auto& s = sound->keyOrder;
  CHECK(s.front() == "external_auditory_canal");
  CHECK(s.back() == "vestibule");
  CHECK(position(s, "tympanic_cavity") > 0);
  CHECK(position(s, "stapes") > position(s, "tympanic_cavity"));
  auto nerve = quiz::resolveQuestion(findQuestion(p.course, "facial_nerve.order_iac_to_middle_ear"), *p.keys);
  REQUIRE(nerve);
  const auto& n = nerve->keyOrder;
  CHECK(n.front() == "internal_auditory_canal");
  CHECK(n.back() == "tympanic_cavity");
  CHECK(position(n, "facial_nerve") > 0);
}

TEST_CASE("PhantomKeys_IdentifyDistractorsComeFromTheTargetsNeighbourhood") {
  // Locality, for every structure as an identify target (lesson questions and exam items alike):
  // no structure left out lies nearer the target in space than a distractor offered, and every
  // distractor lies nearer than the median structure, so a choice cannot be ruled out by region.
  PhantomKeys& p = phantomKeys();
  int checked = 0;
  for (const Structure& target : p.dataset.structures) {
    CAPTURE(target.id);
    quiz::Question q;
    q.id = "locality." + target.id;
    q.kind = quiz::QuestionKind::Identify;
    q.target = target.id;
    q.distractors = 3;
    auto r = quiz::resolveQuestion(q, *p.keys);
    REQUIRE_MESSAGE(r, (r ? "" : r.error().message));
    auto centre = p.keys->centroidMm(target.id);
    REQUIRE(centre);
    std::vector<double> all;
    double farthestChoice = 0;
    for (const Structure& other : p.dataset.structures) {
      if (other.id == target.id) continue;
      auto c = p.keys->centroidMm(other.id);
      REQUIRE(c);
      all.push_back(norm(*c - *centre));
      if (position(r->choices, other.id) >= 0) farthestChoice = std::max(farthestChoice, all.back());
    }
    std::sort(all.begin(), all.end());
    CHECK(farthestChoice <= all[all.size() / 2]);
    auto d = p.keys->distancesFrom(target.id);
    REQUIRE(d);
    for (const Structure& other : p.dataset.structures) {
      if (other.id == target.id || position(r->choices, other.id) >= 0 || !std::isfinite((*d)[other.id])) continue;
      auto c = p.keys->centroidMm(other.id);
      CHECK_MESSAGE(norm(*c - *centre) >= farthestChoice, other.id);
    }
    ++checked;
  }
  MESSAGE("identify targets checked for neighbourhood distractors: " << checked);
  CHECK(checked == int(p.dataset.structures.size()));
}

TEST_CASE("ShippedCourse_NameQuestionsAcceptSynonymsButNotTheNeighbouringCanal") {
  PhantomKeys& p = phantomKeys();
  test::InMemoryCurriculum curriculum;
  curriculum.courseList = {p.course};
  curriculum.datasets["phantom"] = phantomStructures();
  test::InMemoryProgress progress;
  LessonEngine engine(curriculum, progress, *p.keys);
  REQUIRE(engine.start(1, "inner_ear", LessonMode::QuizOnly));
  REQUIRE(engine.current());
  // Go to the name question of the lateral canal.
  while (engine.current()->questionId != "inner_ear.name_lateral_canal") {
    auto q = engine.currentQuestion();
    REQUIRE(q);
    REQUIRE(engine.answer(test::rightAnswerTo(*q, p.dataset.structures), {}, 1));
    REQUIRE(engine.next());
  }
  quiz::Answer a;
  a.text = "Horizontal  semi-circular canal";
  auto g = engine.answer(a, {}, 1);
  REQUIRE(g);
  CHECK(g->correct);

  // A grading context built like the engine's: "external auditory canal" is not a typo of the internal one.
  quiz::GradingContext context;
  for (const Structure& s : phantomStructures()) {
    quiz::NameEntry e{.structureId = s.id, .names = {s.displayName}, .baseName = ""};
    for (const std::string& syn : p.course.synonyms[s.id]) e.names.push_back(syn);
    context.names.push_back(e);
  }
  quiz::ResolvedQuestion iac;
  iac.question.id = "t";
  iac.question.kind = quiz::QuestionKind::Name;
  iac.question.target = "internal_auditory_canal";
  a.text = "external auditory canal";
  CHECK_FALSE(quiz::grade(iac, a, context)->correct);
  a.text = "internal acoustic meatus";
  CHECK(quiz::grade(iac, a, context)->correct);
  a.text = "internal auditory canl";
  CHECK(quiz::grade(iac, a, context)->correct);
}

TEST_CASE("ShippedCourse_EveryLessonPlaysThroughInOrderWithPrerequisites") {
  PhantomKeys& p = phantomKeys();
  test::InMemoryCurriculum curriculum;
  curriculum.courseList = {p.course};
  curriculum.datasets["phantom"] = phantomStructures();
  test::InMemoryProgress progress;
  LessonEngine engine(curriculum, progress, *p.keys);
  // The last lesson is locked until its prerequisites are done.
  auto locked = engine.start(1, "mastoidectomy_landmarks");
  REQUIRE_FALSE(locked);
  CHECK(locked.error().message.find("'facial_nerve'") != std::string::npos);
  CHECK(locked.error().message.find("'middle_ear'") != std::string::npos);

  std::size_t answered = 0;
  for (const Lesson& lesson : p.course.lessons) {
    REQUIRE_MESSAGE(engine.start(1, lesson.id), lesson.id);
    while (!engine.atEnd()) {
      auto step = engine.current();
      REQUIRE(step);
      if (step->kind == StepKind::Question) {
        auto q = engine.currentQuestion();
        REQUIRE(q);
        auto g = engine.answer(test::rightAnswerTo(*q, p.dataset.structures), {}, 100);
        REQUIRE(g);
        CHECK_MESSAGE(g->correct, q->question.id);
        ++answered;
      }
      REQUIRE(engine.next());
    }
    auto score = engine.finish();
    REQUIRE(score);
    CHECK(*score == doctest::Approx(1.0));
  }
  CHECK(progress.responseList.size() == answered);
  CHECK(answered >= 20);
}

TEST_CASE("ShippedCourse_ExamDrawsItsItemsOnThePhantomAndEveryQuestionHasAScene") {
  PhantomKeys& p = phantomKeys();
  REQUIRE_FALSE(p.course.exams.empty());
  for (const ExamSpec& exam : p.course.exams) {
    CAPTURE(exam.id);
    auto items = drawExamItems(exam, p.dataset.structures, *p.keys, "phantom-test", &p.course);
    REQUIRE_MESSAGE(items, (items ? "" : items.error().message));
    CHECK(int(items->size()) == exam.count);
    int locate = 0;
    for (const ExamItem& item : *items) {
      CHECK(p.keys->hasStructure(item.scene.structure));
      const quiz::Question& q = item.question.question;
      if (q.kind != quiz::QuestionKind::Locate) continue;
      ++locate;
      CHECK(item.scene.structure != q.target);
      // Chosen like a lesson view: the scene and tolerance of the lesson question locating it.
      const Step* lesson = lessonLocateStep(p.course, q.target);
      REQUIRE_MESSAGE(lesson != nullptr, q.id);
      CHECK(item.scene.structure == sceneFor(*lesson).structure);
      CHECK((item.scene.view == sceneFor(*lesson).view));
      CHECK(q.toleranceMm == lesson->question.toleranceMm);
    }
    MESSAGE("exam " << exam.id << ": " << items->size() << " items, " << locate << " locate items in lesson views");
    for (const std::string& pre : exam.prerequisites) {
      const bool known = std::any_of(p.course.lessons.begin(), p.course.lessons.end(), [&](const Lesson& l) { return l.id == pre; });
      CHECK_MESSAGE(known, pre);
    }
  }
  // Every question of the shipped course says what the view shows while it is asked.
  for (const Lesson& l : p.course.lessons)
    for (const Step& s : l.steps)
      if (s.kind == StepKind::Question) {
        CHECK_MESSAGE(s.scene.has_value(), s.question.id);
        CHECK_MESSAGE(p.keys->hasStructure(sceneFor(s).structure), s.question.id);
      }
}

TEST_CASE("ShippedCourse_ExamDraw_EachStructuresKindIsEvenAmongTheKindsItCanBeAskedIn_NoItemTwice") {
  PhantomKeys& p = phantomKeys();
  REQUIRE_FALSE(p.course.exams.empty());
  for (const ExamSpec& exam : p.course.exams) {
    CAPTURE(exam.id);
    // The pool: every (structure, kind) the exam can ask — locate only where a lesson locates it.
    std::set<std::string> pool;
    std::map<std::string, int> kindsOf;
    for (const std::string& id : exam.structures)
      for (quiz::QuestionKind k : exam.kinds)
        if (k != quiz::QuestionKind::Locate || lessonLocateStep(p.course, id)) {
          pool.insert(exam.id + "." + quiz::toString(k) + "." + id);
          ++kindsOf[id];
        }
    // An exam asking the whole pool draws exactly the pool, for any seed.
    ExamSpec whole = exam;
    whole.count = int(pool.size());
    for (const char* seed : {"class|AAAA2222|x", "class|ZZZZ9999|y", "phantom-test"}) {
      auto items = drawExamItems(whole, p.dataset.structures, *p.keys, seed, &p.course);
      REQUIRE_MESSAGE(items, (items ? "" : items.error().message));
      std::set<std::string> drawn;
      for (const ExamItem& item : *items) CHECK(drawn.insert(item.question.question.id).second);
      CHECK(drawn == pool);
    }
    ExamSpec tooMany = exam;
    tooMany.count = int(pool.size()) + 1;
    CHECK_FALSE(drawExamItems(tooMany, p.dataset.structures, *p.keys, "x", &p.course));

    // The exam as shipped, over many class draws: each structure's kind is even among its kinds.
    const int draws = 300;
    std::map<std::string, int> perKind, perItem;
    for (int s = 0; s < draws; ++s) {
      auto items = drawExamItems(exam, p.dataset.structures, *p.keys, "class|C" + std::to_string(s * 7919) + "|" + exam.id, &p.course);
      REQUIRE(items);
      for (const ExamItem& item : *items) {
        ++perKind[quiz::toString(item.question.question.kind)];
        ++perItem[item.question.question.id];
      }
    }
    double expectedLocate = 0;
    for (const auto& [id, n] : kindsOf) expectedLocate += n == int(exam.kinds.size()) ? 1.0 / n : 0.0;
    for (const auto& [kind, n] : perKind)
      MESSAGE(exam.id << ": " << kind << " " << double(n) / draws << " items a draw (pool: "
                      << std::count_if(pool.begin(), pool.end(), [&](const std::string& q) { return q.find("." + kind + ".") != std::string::npos; })
                      << " of " << pool.size() << ")");
    MESSAGE("locate expected " << expectedLocate * exam.count / double(exam.structures.size()) << " a draw");
    if (exam.count == int(exam.structures.size()))
      for (const std::string& item : pool) {
        const std::string id = item.substr(item.rfind('.') + 1);
        const double expected = 1.0 / kindsOf[id];
        CAPTURE(item);
        CHECK(std::abs(double(perItem[item]) / draws - expected) < 0.1);  // > 3.5 standard deviations
      }
  }
}
