#include "render_fixture.h"

#include <doctest/doctest.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "render/gl/egl_context.h"
#include "test_support.h"

namespace at::test {

namespace {

// The context and the ray caster, released in that order (GL objects while their context lives,
// then the context and its display) at the end of the test run, from inside main. Static
// destruction is too late: NVIDIA's EGL (and CUDA) register their own exit-time teardown when they
// load, after this fixture's statics were registered, so they run first and a GL call or
// eglTerminate from a static destructor then touches a dead driver (a segfault at exit).
struct GlFixture {
  std::optional<render::gl::EglContext> context;
  std::optional<render::gl::VolumeRenderer> renderer;
  std::string why;

  void release() {
    renderer.reset();
    context.reset();
  }
};

// Empty by the time static destructors run (the listener below released it).
std::unique_ptr<GlFixture>& fixture() {
  static std::unique_ptr<GlFixture> f;
  return f;
}

void releaseGl() {
  if (fixture()) fixture()->release();
  fixture().reset();
}

// Releases the GL fixture when the run ends (test_run_end is called before main returns).
struct GlReleaseListener : doctest::IReporter {
  explicit GlReleaseListener(const doctest::ContextOptions&) {}
  void report_query(const doctest::QueryData&) override {}
  void test_run_start() override {}
  void test_run_end(const doctest::TestRunStats&) override { releaseGl(); }
  void test_case_start(const doctest::TestCaseData&) override {}
  void test_case_reenter(const doctest::TestCaseData&) override {}
  void test_case_end(const doctest::CurrentTestCaseStats&) override {}
  void test_case_exception(const doctest::TestCaseException&) override {}
  void subcase_start(const doctest::SubcaseSignature&) override {}
  void subcase_end() override {}
  void log_assert(const doctest::AssertData&) override {}
  void log_message(const doctest::MessageData&) override {}
  void test_case_skipped(const doctest::TestCaseData&) override {}
};

REGISTER_LISTENER("gl_release", 1, GlReleaseListener);

}  // namespace

render::gl::VolumeRenderer* glRenderer() {
  static bool tried = false;
  if (!tried) {
    tried = true;
    fixture() = std::make_unique<GlFixture>();
    GlFixture* f = fixture().get();
    auto ctx = render::gl::EglContext::create();
    if (!ctx) {
      f->why = ctx.error().message;
    } else {
      f->context.emplace(std::move(*ctx));
      auto r = render::gl::VolumeRenderer::create();
      if (!r) {
        f->why = r.error().message;
      } else {
        f->renderer.emplace(std::move(*r));
        std::printf("render tests on: %s\n", f->context->description().c_str());
      }
    }
  }
  GlFixture* f = fixture().get();
  if (!f || !f->renderer) {
    at::test::skipf("GL render test needs an EGL OpenGL 4.3 context (%s)", f ? f->why.c_str() : "released");
    return nullptr;
  }
  return &*f->renderer;
}

}  // namespace at::test
