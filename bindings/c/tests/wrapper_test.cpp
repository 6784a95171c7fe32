// The C++ wrapper (examples/brdftab.hpp) as a renderer calls it (driven by tests/c_programs.rs,
// built with -fsanitize=undefined where the compiler has it): empty batches straight from empty
// std::vectors (data() may be nullptr), and the single-pair calls against the batch calls.
// Prints "ok" and exits 0, or a FAIL line and exits 1.
#include <cstdio>
#include <vector>

#include "brdftab.hpp"

int main() {
    try {
        brdftab::Brdf b("{\"model\": \"ggx\", \"alpha\": 0.3}");
        // Empty batches: n = 0 with nullptr arrays succeeds (the header), through the wrapper too.
        std::vector<brdftab::Vec3> wi, wo, out;
        std::vector<float> f, w;
        std::vector<double> p, u;
        std::vector<unsigned char> d;
        b.eval(wi.size(), wi.data(), wo.data(), f.data());
        b.pdf(wi.size(), wi.data(), wo.data(), p.data());
        b.sample(wo.size(), wo.data(), u.data(), out.data(), p.data(), w.data());
        b.sample(wo.size(), wo.data(), u.data(), out.data(), p.data(), w.data(), d.data());
        // One pair through both paths.
        wi = {{0.3, 0.1, 0.9}};
        wo = {{-0.2, 0.3, 0.8}};
        f.resize(3);
        float g[3];
        b.eval(1, wi.data(), wo.data(), f.data());
        b.eval(wi[0], wo[0], g);
        if (f[0] != g[0] || !(g[0] > 0)) {
            std::fprintf(stderr, "FAIL eval %g vs %g\n", f[0], g[0]);
            return 1;
        }
    } catch (const brdftab::Error &e) {
        std::fprintf(stderr, "FAIL %s\n", e.what());
        return 1;
    }
    std::printf("ok\n");
    return 0;
}
