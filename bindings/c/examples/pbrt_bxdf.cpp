// Uses the pbrt-v4-style adapter the way an integrator does: a Monte Carlo estimate of the
// directional albedo from Sample_f (f cos / pdf), printed beside brdftab's own albedo — or, for
// a source that is not reciprocal, beside an estimate of the same integral by uniform sampling.
// theta_deg in (90, 180) views the back side: pbrt's BxDFs (and the adapter) are two-sided, so it
// prints the albedo at 180 - theta_deg.
//
//   g++ -std=c++17 -O2 pbrt_bxdf.cpp -I../include -L../../../target/release -lbrdftab_c -o pbrt_bxdf
//   LD_LIBRARY_PATH=../../../target/release ./pbrt_bxdf SOURCE [theta_deg]
#include <cstdio>
#include <cstdlib>
#include <random>

#include "pbrt_bxdf.hpp"

constexpr double BRDFTAB_PI = 3.14159265358979323846;

int main(int argc, char **argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s SOURCE [theta_deg]\n", argv[0]);
        return 2;
    }
    double theta = (argc > 2 ? std::atof(argv[2]) : 30.0) * BRDFTAB_PI / 180.0;
    try {
        brdftab::Brdf b(argv[1]);
        pbrt_like::BrdftabBxDF bxdf(b);
        pbrt_like::Vector3f wo{float(std::sin(theta)), 0.f, float(std::cos(theta))};
        std::mt19937 rng(1);
        std::uniform_real_distribution<float> u01(0.f, 0.99999994f);
        const int n = 200000;
        double sum[3] = {0, 0, 0};
        for (int k = 0; k < n; ++k) {
            auto s = bxdf.Sample_f(wo, 0.f, {u01(rng), u01(rng)});
            if (!s) continue;
            for (int c = 0; c < 3; ++c) sum[c] += s->f[c] * std::abs(s->wi.z) / s->pdf;
        }
        std::printf("mc %.6f %.6f %.6f\n", sum[0] / n, sum[1] / n, sum[2] / n);
        // brdftab's albedo integrates over wo for a fixed wi; the estimate above over wi for a
        // fixed wo (pbrt's Sample_f). They are one number only for a reciprocal source; for
        // another (the original Phong) the same integral is estimated by uniform sampling of
        // the hemisphere, f cos θi · 2π, through f() alone.
        // The back side (wo.z < 0) reflects as the front does at the mirrored angle.
        const double front = wo.z < 0 ? BRDFTAB_PI - theta : theta;
        if (b.flags() & BRDFTAB_RECIPROCAL) {
            auto a = b.albedo(front);
            std::printf("albedo %.6f %.6f %.6f\n", a[0], a[1], a[2]);
        } else {
            double uni[3] = {0, 0, 0};
            for (int k = 0; k < n; ++k) {
                double z = u01(rng), phi = 2 * BRDFTAB_PI * u01(rng), r = std::sqrt(1 - z * z);
                pbrt_like::Vector3f wi{float(r * std::cos(phi)), float(r * std::sin(phi)),
                                       float(wo.z < 0 ? -z : z)};
                auto f = bxdf.f(wo, wi);
                for (int c = 0; c < 3; ++c) uni[c] += f[c] * z * 2 * BRDFTAB_PI;
            }
            std::printf("uniform %.6f %.6f %.6f\n", uni[0] / n, uni[1] / n, uni[2] / n);
        }
    } catch (const brdftab::Error &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
