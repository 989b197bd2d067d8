#include "core/stats.h"

#include <cmath>
#include <cstdio>

namespace rs {

void Stats::addTime(const std::string& stage, double s) {
    for (auto& [name, v] : seconds)
        if (name == stage) { v += s; return; }
    seconds.emplace_back(stage, s);
}

void Stats::setCount(const std::string& name, double value) {
    for (auto& [n, v] : counts)
        if (n == name) { v = value; return; }
    counts.emplace_back(name, value);
}

double Stats::time(const std::string& stage) const {
    for (const auto& [name, v] : seconds)
        if (name == stage) return v;
    return 0.0;
}

double Stats::count(const std::string& name) const {
    for (const auto& [n, v] : counts)
        if (n == name) return v;
    return 0.0;
}

double Stats::totalSeconds() const {
    double t = 0;
    for (const auto& [name, v] : seconds) t += v;
    return t;
}

std::string jsonString(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') { out += '\\'; out += c; }
        else if (static_cast<unsigned char>(c) < 0x20) { char b[8]; std::snprintf(b, sizeof b, "\\u%04x", c); out += b; }
        else out += c;
    }
    return out + "\"";
}

static std::string jsonObject(const std::vector<std::pair<std::string, double>>& kv) {
    std::string out = "{";
    for (size_t i = 0; i < kv.size(); ++i) {
        char b[64];
        if (std::isfinite(kv[i].second))
            std::snprintf(b, sizeof b, "%.9g", kv[i].second);
        else
            std::snprintf(b, sizeof b, "null");  // JSON has no NaN or infinity
        out += (i ? ", " : "") + jsonString(kv[i].first) + ": " + b;
    }
    return out + "}";
}

std::string Stats::json() const {
    char total[64];
    std::snprintf(total, sizeof total, "%.9g", totalSeconds());
    return "{\n  \"seconds\": " + jsonObject(seconds) + ",\n  \"total_seconds\": " + total +
           ",\n  \"counts\": " + jsonObject(counts) + "\n}\n";
}

}  // namespace rs
