// The C++ baseline of igemu's post stage (benches/post.rs): the gamma LUT and the ordered
// dither of one frame, a plain integer model as a hand-written C++ testbench would have it
// (no ac_fixed: its headers are not packaged here). Compiled with g++ -O2 by the bench.
//
// Input files in the directory given as argv[1] (little-endian u32 arrays):
//   params: width, height, lut_entries, frac_bits (s), mask_side (n), mask_bits (b), out_max,
//           frame_shift (the frame word's fraction bits, dropped before the lookup)
//   acc: width*height frame codes; lut: lut_entries LUT codes (s fraction bits);
//   mask: n*n ranks (row-major)
// Writes out.u32 (width*height DAC codes) and prints "best_ns <t> sat <k>" for the best of
// argv[2] rounds.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

static std::vector<uint32_t> read(const std::string& path) {
    std::vector<uint32_t> v;
    FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) {
        std::fprintf(stderr, "cannot open %s\n", path.c_str());
        std::exit(2);
    }
    uint32_t x;
    while (std::fread(&x, 4, 1, f) == 1) v.push_back(x);
    std::fclose(f);
    return v;
}

// One frame: y = lut[min(acc >> shift, last)]; code = floor(y / 2^s + (rank + 1/2) / 2^b), saturated.
static uint64_t chain(const uint32_t* acc, const uint32_t* lut, uint32_t last,
                      const uint32_t* mask, uint32_t n, uint32_t s, uint32_t b,
                      uint32_t out_max, uint32_t shift, uint32_t w, uint32_t h,
                      uint32_t* out) {
    uint64_t sat = 0;
    for (uint32_t y = 0; y < h; ++y) {
        const uint32_t* mrow = mask + (y & (n - 1)) * n;
        for (uint32_t x = 0; x < w; ++x) {
            uint32_t a = acc[y * w + x] >> shift;
            uint64_t v = lut[a < last ? a : last];
            uint64_t rank = mrow[x & (n - 1)];
            uint64_t c = ((v << (b + 1)) + ((2 * rank + 1) << s)) >> (s + b + 1);
            sat += c > out_max;
            out[y * w + x] = static_cast<uint32_t>(c > out_max ? out_max : c);
        }
    }
    return sat;
}

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: post_chain DIR ROUNDS\n");
        return 2;
    }
    std::string dir = argv[1];
    int rounds = std::atoi(argv[2]);
    std::vector<uint32_t> p = read(dir + "/params.u32");
    std::vector<uint32_t> acc = read(dir + "/acc.u32");
    std::vector<uint32_t> lut = read(dir + "/lut.u32");
    std::vector<uint32_t> mask = read(dir + "/mask.u32");
    if (p.size() != 8 || acc.size() != size_t(p[0]) * p[1] || lut.size() != p[2] ||
        mask.size() != size_t(p[4]) * p[4]) {
        std::fprintf(stderr, "bad input sizes\n");
        return 2;
    }
    std::vector<uint32_t> out(acc.size());
    double best = 1e30;
    uint64_t sat = 0;
    for (int r = 0; r < rounds; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        sat = chain(acc.data(), lut.data(), p[2] - 1, mask.data(), p[4], p[3], p[5], p[6], p[7],
                    p[0], p[1], out.data());
        auto t1 = std::chrono::steady_clock::now();
        double ns = std::chrono::duration<double, std::nano>(t1 - t0).count();
        if (ns < best) best = ns;
    }
    FILE* f = std::fopen((dir + "/out.u32").c_str(), "wb");
    if (!f || std::fwrite(out.data(), 4, out.size(), f) != out.size()) return 2;
    std::fclose(f);
    std::printf("best_ns %.0f sat %llu\n", best, static_cast<unsigned long long>(sat));
    return 0;
}
