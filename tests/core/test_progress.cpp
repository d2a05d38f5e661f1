// The progress line of long loops (progress.hpp): items read back from a checkpoint count toward k/n but not
// toward the rate, so a resumed run's ETA comes from the items it runs, not from instant ones.
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <unistd.h>

#include <chrono>
#include <regex>
#include <sstream>
#include <thread>

namespace sflsh {

namespace {

/// Routes the project logger to a string for the scope, then puts the previous one back.
class CapturedLog {
 public:
  CapturedLog() : previous_(logger()) {
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(text_);
    sink->set_pattern("%v");
    auto captured = std::make_shared<spdlog::logger>("sflsh", sink);
    captured->set_level(spdlog::level::info);
    set_logger(captured);
  }
  ~CapturedLog() { set_logger(previous_); }
  std::string text() const { return text_.str(); }

 private:
  std::ostringstream text_;
  std::shared_ptr<spdlog::logger> previous_;
};

}  // namespace

TEST(Progress, ItemsDoneEarlierDoNotCountTowardTheRate) {
  if (::isatty(STDERR_FILENO) == 1) GTEST_SKIP() << "a terminal gets the live line, not log lines";
  CapturedLog log;
  {
    Progress progress("fits", 4);
    progress.skip(2);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    progress.advance();
  }
  const std::string text = log.text();
  // Only skipped items so far: no rate to project from.
  EXPECT_NE(text.find("fits 2/4, 2 done earlier (0.0/s, ETA unknown)"), std::string::npos) << text;
  // One item in ≥ 50 ms: at most 20 items per second (the two read back would make it ≥ 3 per 50 ms otherwise).
  std::smatch match;
  const std::string after = text.substr(text.find("fits 3/4"));
  ASSERT_TRUE(std::regex_search(after, match, std::regex(R"(fits 3/4, 2 done earlier \(([0-9.]+)/s, ETA ([0-9]+)s\))")))
      << text;
  EXPECT_LE(std::stod(match[1].str()), 20.5);
  EXPECT_GT(std::stod(match[1].str()), 0.0);
}

}  // namespace sflsh
