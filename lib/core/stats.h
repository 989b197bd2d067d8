// Per-stage wall times and counts of a render, for --stats-json and the EXR header.
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace rs {

constexpr double kMB = 1024.0 * 1024.0;  // bytes in the *_mb counts

// Counters declared once. A list macro names each counter's member and its --stats-json name,
//   #define MY_COUNTERS(X) X(nodes, "tree_nodes") X(bricks, "tree_bricks")
// and a struct gets its members, their sum and their report from it:
//   struct MyStats { MY_COUNTERS(RS_COUNTER_MEMBER)
//       void add(const MyStats& o) { MY_COUNTERS(RS_COUNTER_ADD) }
//       void report(Stats& stats) const { MY_COUNTERS(RS_COUNTER_REPORT) } };
#define RS_COUNTER_MEMBER(member, name) uint64_t member = 0;
#define RS_COUNTER_ADD(member, name) member += o.member;
#define RS_COUNTER_REPORT(member, name) stats.setCount(name, double(member));

// `s` as a JSON string literal, quotes included.
std::string jsonString(const std::string& s);

struct Stats {
    std::vector<std::pair<std::string, double>> seconds;  // stage → wall time, in order
    std::vector<std::pair<std::string, double>> counts;   // name → value, in order

    void addTime(const std::string& stage, double s);
    void setCount(const std::string& name, double value);
    double time(const std::string& stage) const;  // 0 when absent
    double count(const std::string& name) const;  // 0 when absent
    double totalSeconds() const;
    std::string json() const;
};

class Timer {
public:
    Timer() : start_(std::chrono::steady_clock::now()) {}
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }

private:
    std::chrono::steady_clock::time_point start_;
};

// A time the user asked a render to end by: seconds on a Timer's clock (no clock: none).
struct Deadline {
    const Timer* clock = nullptr;
    double seconds = 0.0;
    // Whether it has passed, or will have in `after` seconds.
    bool passed(double after = 0.0) const { return clock && clock->seconds() + after >= seconds; }
};

}  // namespace rs
