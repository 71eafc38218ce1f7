// StockExtractor (stock_extractor.hpp) and the growing heap it can run a fork's extractor on: a
// replacement of the global operator new that, while a kGrowing call runs on this thread, hands
// out the fork's octree nodes (allocations of exactly the size of its std::list node) from one
// arena in increasing addresses, never reusing one within the call, so that ORB-SLAM2's octree,
// which orders nodes of equal size by address, orders them by creation. The nodes die with the
// call; the arena starts again at the next one, and refuses to while one is still alive.
#include "stock_extractor.hpp"

#include <sys/mman.h>

#include <cstddef>
#include <cstdlib>
#include <new>
#include <stdexcept>

#include "stock_detail.hpp"

namespace {

constexpr std::size_t kArenaBytes = std::size_t{4} << 30;  // reserved, committed page by page

struct Arena {
  char* base = nullptr;
  std::size_t used = 0;
  std::size_t live = 0;  ///< arena allocations not yet released
};

Arena& arena() {
  static Arena a = [] {
    Arena fresh;
    void* p = mmap(nullptr, kArenaBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (p == MAP_FAILED) throw std::runtime_error("stock_extractor: cannot reserve the growing heap");
    fresh.base = static_cast<char*>(p);
    return fresh;
  }();
  return a;
}

thread_local std::size_t growing_size = 0;  // the node size while a kGrowing call runs, else 0

bool in_arena(const void* p) {
  const Arena& a = arena();
  const char* c = static_cast<const char*>(p);
  return a.base != nullptr && c >= a.base && c < a.base + kArenaBytes;
}

void* allocate(std::size_t n) {
  if (growing_size != 0 && n == growing_size) {
    Arena& a = arena();
    const std::size_t rounded = (n + 15) / 16 * 16;
    if (a.used + rounded > kArenaBytes) throw std::runtime_error("stock_extractor: the growing heap is full");
    void* p = a.base + a.used;
    a.used += rounded;
    ++a.live;
    return p;
  }
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}

void release(void* p) noexcept {
  if (p == nullptr) return;
  if (in_arena(p)) {
    --arena().live;
    return;
  }
  std::free(p);
}

}  // namespace

void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void operator delete(void* p) noexcept { release(p); }
void operator delete[](void* p) noexcept { release(p); }
void operator delete(void* p, std::size_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t) noexcept { release(p); }

namespace affine_orb::stock {

struct StockExtractor::Impl {
  detail::ForkEntry entry;
};

StockExtractor::StockExtractor(Fork fork, int nfeatures, float scale_factor, int levels, int ini, int min)
    : impl_(new Impl) {
  arena();  // reserved before any call can need it
  impl_->entry = fork == Fork::kOrbSlam2 ? detail::orbslam2(nfeatures, scale_factor, levels, ini, min)
                                         : detail::orbslam3(nfeatures, scale_factor, levels, ini, min);
}

StockExtractor::~StockExtractor() { impl_->entry.release(impl_->entry.extractor); }

StockFrame StockExtractor::extract(const cv::Mat& image, Heap heap, std::vector<int> lapping) {
  if (heap == Heap::kSystem) return impl_->entry.run(impl_->entry.extractor, image, lapping);
  Arena& a = arena();
  if (a.live != 0) throw std::logic_error("stock_extractor: an octree node outlived its call");
  a.used = 0;
  growing_size = impl_->entry.node_size;
  try {
    StockFrame frame = impl_->entry.run(impl_->entry.extractor, image, lapping);
    growing_size = 0;
    return frame;
  } catch (...) {
    growing_size = 0;
    throw;
  }
}

}  // namespace affine_orb::stock
