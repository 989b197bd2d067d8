// In-process comparison of two revisions' cylinder traversal (run.sh builds it): both sides'
// code in one program, timed alternately on the same cylinders, a measurement pair at a time.
// Separate runs of two builds on a shared machine spread by ±15 %; pairs taken a fraction of a
// second apart in one process share the machine's state, and their ratios' median settles.
//   traversal_ab ROUNDS [RADIUS ...]     (defaults 15, radii 4 8; AB_SECONDS: a measurement's
//                                          length, default 0.25, for side a)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace rs_a {
struct AbSide;
AbSide* abSetUp();
double abRate(AbSide*, float radius, bool allThreads, size_t count, double& checksum);
}  // namespace rs_a
namespace rs_b {
struct AbSide;
AbSide* abSetUp();
double abRate(AbSide*, float radius, bool allThreads, size_t count, double& checksum);
}  // namespace rs_b

namespace {
double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
}  // namespace

int main(int argc, char** argv) {
    const int rounds = argc > 1 ? std::max(1, std::atoi(argv[1])) : 15;
    std::vector<float> radii;
    for (int i = 2; i < argc; ++i) radii.push_back(std::strtof(argv[i], nullptr));
    if (radii.empty()) radii = {4.f, 8.f};
    const char* secondsText = std::getenv("AB_SECONDS");
    const double seconds = secondsText ? std::atof(secondsText) : 0.25;
    rs_a::AbSide* a = rs_a::abSetUp();
    rs_b::AbSide* b = rs_b::abSetUp();
    double checkA = 0, checkB = 0;
    std::printf("in-process comparison, %d pairs a row, side a first in odd pairs; b/a: pairwise ratios\n", rounds);
    std::printf("%6s %8s | %12s %12s | %9s %9s %9s\n", "radius", "threads", "a (c/s)", "b (c/s)", "b/a", "min", "max");
    for (float radius : radii)
        for (int all = 0; all < 2; ++all) {
            // As many cylinders as side a runs in `seconds`, the same count for both sides.
            double sink = 0;
            const size_t count = std::max<size_t>(256, size_t(rs_a::abRate(a, radius, all, 2048, sink) * seconds));
            std::vector<double> rateA, rateB, ratio;
            for (int k = 0; k < rounds; ++k) {
                double x, y;
                if (k % 2 == 0) {
                    x = rs_a::abRate(a, radius, all, count, checkA);
                    y = rs_b::abRate(b, radius, all, count, checkB);
                } else {
                    y = rs_b::abRate(b, radius, all, count, checkB);
                    x = rs_a::abRate(a, radius, all, count, checkA);
                }
                rateA.push_back(x), rateB.push_back(y), ratio.push_back(y / x);
            }
            std::printf("%6g %8s | %12.0f %12.0f | %9.3f %9.3f %9.3f\n", radius, all ? "all" : "1", median(rateA), median(rateB),
                        median(ratio), *std::min_element(ratio.begin(), ratio.end()), *std::max_element(ratio.begin(), ratio.end()));
            std::fflush(stdout);
        }
    std::printf("checksums (the sums of V; equal when both sides visit the same samples): a %.9e b %.9e\n", checkA, checkB);
}
