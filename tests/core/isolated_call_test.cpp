#include "core/isolated_call.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <stdexcept>
#include <string>
#include <thread>

#include "core/error.hpp"

namespace lasercell {
namespace {

TEST(IsolatedCall, ReturnsTheBytesTheWorkProduced) {
  const std::string big(300000, 'x');  // more than a pipe buffer holds
  const IsolatedOutcome out = RunIsolated([&] { return big + "end"; }, 30);
  ASSERT_EQ(out.kind, IsolatedOutcome::Kind::kReturned);
  EXPECT_EQ(out.bytes, big + "end");
  EXPECT_EQ(RunIsolated([] { return std::string(); }, 30).bytes, "");
}

TEST(IsolatedCall, ExceptionsComeBackWithTheirMessages) {
  const IsolatedOutcome input =
      RunIsolated([]() -> std::string { throw InputError("bad file"); }, 30);
  EXPECT_EQ(input.kind, IsolatedOutcome::Kind::kInputError);
  EXPECT_EQ(input.message, "bad file");
  const IsolatedOutcome other =
      RunIsolated([]() -> std::string { throw std::out_of_range("index 7"); }, 30);
  EXPECT_EQ(other.kind, IsolatedOutcome::Kind::kOtherError);
  EXPECT_EQ(other.message, "index 7");
}

TEST(IsolatedCall, AFaultInTheWorkEndsTheChildNotTheCaller) {
  const IsolatedOutcome out = RunIsolated(
      []() -> std::string {
        std::raise(SIGSEGV);
        return "not reached";
      },
      30);
  EXPECT_EQ(out.kind, IsolatedOutcome::Kind::kCrashed);
  EXPECT_EQ(out.signal, SIGSEGV);
  EXPECT_TRUE(IsFaultSignal(out.signal));
  EXPECT_FALSE(IsFaultSignal(SIGABRT));
}

TEST(IsolatedCall, WorkThatDoesNotFinishIsKilledAtTheTimeout) {
  const auto start = std::chrono::steady_clock::now();
  const IsolatedOutcome out = RunIsolated(
      []() -> std::string {
        for (;;) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      },
      0.3);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(out.kind, IsolatedOutcome::Kind::kTimedOut);
  EXPECT_GE(seconds, 0.3);
  EXPECT_LT(seconds, 30.0);  // bounded, not a timing assertion
}

TEST(IsolatedCall, TheWorkCannotChangeTheCallersMemory) {
  int value = 1;
  const IsolatedOutcome out = RunIsolated(
      [&] {
        value = 2;
        return std::to_string(value);
      },
      30);
  EXPECT_EQ(out.bytes, "2");
  EXPECT_EQ(value, 1);
}

}  // namespace
}  // namespace lasercell
