#include "bench_plot.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>

namespace visbuf::tools {

std::vector<bool> paretoFront(const std::vector<double>& timeMs, const std::vector<double>& psnr, double psnrTolerance) {
  const size_t n = std::min(timeMs.size(), psnr.size());
  std::vector<bool> front(n, true);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n && front[i]; ++j) {
      if (i == j) continue;
      const bool noWorse = timeMs[j] <= timeMs[i] && psnr[j] >= psnr[i] - psnrTolerance;
      const bool better = timeMs[j] < timeMs[i] || psnr[j] > psnr[i] + psnrTolerance;
      if (noWorse && better) front[i] = false;
    }
  return front;
}

namespace {

std::string xmlEscape(const std::string& s) {
  std::string out;
  for (char ch : s) {
    switch (ch) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += ch;
    }
  }
  return out;
}

const char* cullColour(const std::string& cull) {
  if (cull == "none") return "#d62728";
  if (cull == "frustum") return "#1f77b4";
  if (cull == "occlusion") return "#2ca02c";
  return "#7f7f7f";
}

std::string marker(const std::string& path, double x, double y, const char* colour) {
  if (path == "gbuffer")  // diamond
    return fmt::format(R"~(<polygon points="{:.1f},{:.1f} {:.1f},{:.1f} {:.1f},{:.1f} {:.1f},{:.1f}" fill="{}" fill-opacity="0.85" stroke="#000" stroke-width="0.6"/>)~",
                       x, y - 6, x + 6, y, x, y + 6, x - 6, y, colour);
  if (path == "forward")
    return fmt::format(R"~(<rect x="{:.1f}" y="{:.1f}" width="9" height="9" fill="{}" fill-opacity="0.85" stroke="#000" stroke-width="0.6"/>)~",
                       x - 4.5, y - 4.5, colour);
  return fmt::format(R"~(<circle cx="{:.1f}" cy="{:.1f}" r="5" fill="{}" fill-opacity="0.85" stroke="#000" stroke-width="0.6"/>)~",
                     x, y, colour);
}

std::string formatTick(double v) {
  if (v >= 1000) return fmt::format("{:.0f}", v);
  return fmt::format("{:g}", v);
}

constexpr double kPanelW = 470, kPanelH = 380;
constexpr double kLeft = 62, kRight = 18, kTop = 34, kBottom = 52;
constexpr double kInfBand = 26;  // room above the finite range for "exact" (infinite PSNR) points

std::string renderPanel(const PlotPanel& panel, double ox, double oy) {
  std::string s;
  const double plotW = kPanelW - kLeft - kRight, plotH = kPanelH - kTop - kBottom;
  const double x0 = ox + kLeft, y0 = oy + kTop;  // top-left of the plot area
  // Ranges.
  double tMin = INFINITY, tMax = -INFINITY, pMin = INFINITY, pMax = -INFINITY;
  bool anyInf = false;
  for (const PlotPoint& p : panel.points) {
    const double t = std::max(p.timeMs, 1e-6);
    tMin = std::min(tMin, t);
    tMax = std::max(tMax, t);
    if (std::isfinite(p.psnr)) {
      pMin = std::min(pMin, p.psnr);
      pMax = std::max(pMax, p.psnr);
    } else {
      anyInf = true;
    }
  }
  if (!std::isfinite(tMin)) tMin = 1, tMax = 10;
  double lx0 = std::log10(tMin) - 0.08, lx1 = std::log10(tMax) + 0.08;
  if (lx1 - lx0 < 0.5) {
    const double mid = 0.5 * (lx0 + lx1);
    lx0 = mid - 0.25, lx1 = mid + 0.25;
  }
  if (!std::isfinite(pMin)) pMin = 20, pMax = 60;
  double yStep = 1;
  for (double step : {1.0, 2.0, 5.0, 10.0, 20.0, 50.0})
    if ((pMax - pMin + 4) / step <= 8) {
      yStep = step;
      break;
    }
  const double yLo = std::floor((pMin - 1) / yStep) * yStep, yHi = std::ceil((pMax + 1) / yStep) * yStep;
  const double finiteTop = y0 + (anyInf ? kInfBand : 0.0);
  const double finiteH = plotH - (anyInf ? kInfBand : 0.0);
  auto X = [&](double ms) { return x0 + (std::log10(std::max(ms, 1e-6)) - lx0) / (lx1 - lx0) * plotW; };
  auto Y = [&](double db) {
    if (!std::isfinite(db)) return y0 + kInfBand * 0.5;
    return finiteTop + (yHi - db) / (yHi - yLo) * finiteH;
  };

  s += fmt::format(R"~(<g><text x="{:.1f}" y="{:.1f}" font-size="13" font-weight="bold" text-anchor="middle">{}</text>)~"
                   "\n",
                   x0 + plotW / 2, oy + 20, xmlEscape(panel.title));
  s += fmt::format(R"~(<rect x="{:.1f}" y="{:.1f}" width="{:.1f}" height="{:.1f}" fill="#fff" stroke="#333"/>)~" "\n", x0, y0,
                   plotW, plotH);
  // X ticks: 1, 2, 5 per decade.
  for (int d = int(std::floor(lx0)); d <= int(std::ceil(lx1)); ++d)
    for (double m : {1.0, 2.0, 5.0}) {
      const double v = m * std::pow(10.0, d);
      const double lv = std::log10(v);
      if (lv < lx0 || lv > lx1) continue;
      const double x = X(v);
      s += fmt::format(R"~(<line x1="{0:.1f}" y1="{1:.1f}" x2="{0:.1f}" y2="{2:.1f}" stroke="#ddd"/>)~" "\n", x, y0, y0 + plotH);
      s += fmt::format(R"~(<text x="{:.1f}" y="{:.1f}" font-size="11" text-anchor="middle">{}</text>)~" "\n", x,
                       y0 + plotH + 15, formatTick(v));
    }
  // Y ticks.
  for (double v = yLo; v <= yHi + 1e-9; v += yStep) {
    const double y = Y(v);
    s += fmt::format(R"~(<line x1="{0:.1f}" y1="{1:.1f}" x2="{2:.1f}" y2="{1:.1f}" stroke="#ddd"/>)~" "\n", x0, y, x0 + plotW);
    s += fmt::format(R"~(<text x="{:.1f}" y="{:.1f}" font-size="11" text-anchor="end">{:g}</text>)~" "\n", x0 - 5, y + 4, v);
  }
  if (anyInf) {
    const double y = Y(INFINITY);
    s += fmt::format(R"~(<line x1="{0:.1f}" y1="{1:.1f}" x2="{2:.1f}" y2="{1:.1f}" stroke="#bbb" stroke-dasharray="2,3"/>)~" "\n",
                     x0, finiteTop, x0 + plotW);
    s += fmt::format(R"~(<text x="{:.1f}" y="{:.1f}" font-size="11" text-anchor="end">exact</text>)~" "\n", x0 - 5, y + 4);
  }
  s += fmt::format(R"~(<text x="{:.1f}" y="{:.1f}" font-size="12" text-anchor="middle">frame time, ms (GPU passes + CPU record; log scale)</text>)~" "\n",
                   x0 + plotW / 2, y0 + plotH + 36);
  s += fmt::format(R"~(<text x="{0:.1f}" y="{1:.1f}" font-size="12" text-anchor="middle" transform="rotate(-90 {0:.1f} {1:.1f})">PSNR vs reference, dB (higher is better)</text>)~" "\n",
                   ox + 16, y0 + plotH / 2);
  // Pareto front: a dashed line through the front's points in time order.
  std::vector<const PlotPoint*> front;
  for (const PlotPoint& p : panel.points)
    if (p.pareto) front.push_back(&p);
  std::sort(front.begin(), front.end(), [](const PlotPoint* a, const PlotPoint* b) { return a->timeMs < b->timeMs; });
  if (front.size() >= 2) {
    std::string pts;
    for (const PlotPoint* p : front) pts += fmt::format("{:.1f},{:.1f} ", X(p->timeMs), Y(p->psnr));
    s += fmt::format(R"~(<polyline points="{}" fill="none" stroke="#555" stroke-width="1.5" stroke-dasharray="6,4"/>)~" "\n", pts);
  }
  for (const PlotPoint* p : front)
    s += fmt::format(R"~(<circle cx="{:.1f}" cy="{:.1f}" r="9" fill="none" stroke="#555" stroke-width="1.2"/>)~" "\n", X(p->timeMs),
                     Y(p->psnr));
  for (const PlotPoint& p : panel.points) s += marker(p.path, X(p.timeMs), Y(p.psnr), cullColour(p.cull)) + "\n";
  // Labels after all markers, each at the first candidate place that overlaps no earlier label.
  struct Box {
    double x, y, w, h;
  };
  std::vector<Box> placed;
  for (const PlotPoint& p : panel.points) {
    const double x = X(p.timeMs), y = Y(p.psnr), w = 6.0 * double(p.label.size()) + 2, h = 10;
    Box best{x + 7, y - 6, w, h};
    const double candidates[][2] = {{7, -6}, {7, 12}, {-7 - w, -6}, {-7 - w, 12}, {7, -17}, {7, 23}, {-7 - w, -17},
                                    {-7 - w, 23}, {7, -28}, {7, 34}};
    for (const auto& d : candidates) {
      Box b{x + d[0], y + d[1], w, h};
      const bool clash = std::any_of(placed.begin(), placed.end(), [&](const Box& o) {
        return b.x < o.x + o.w && o.x < b.x + b.w && b.y - b.h < o.y && o.y - o.h < b.y;
      });
      if (!clash) {
        best = b;
        break;
      }
    }
    placed.push_back(best);
    s += fmt::format(R"~(<text x="{:.1f}" y="{:.1f}" font-size="10" fill="#333">{}</text>)~" "\n", best.x, best.y,
                     xmlEscape(p.label));
  }
  s += "</g>\n";
  return s;
}

}  // namespace

std::string renderBenchSvg(const std::vector<PlotPanel>& panels, const std::string& title,
                           const std::string& subtitle) {
  const size_t n = std::max<size_t>(panels.size(), 1);
  // The subtitle (a command line) wrapped at spaces to the figure's width.
  const double width = std::max(double(n) * kPanelW, 760.0), legendH = 70;
  const size_t perLine = size_t(width / 5.6);
  std::vector<std::string> lines;
  {
    std::string line, word;
    auto flush = [&] {
      if (!word.empty()) {
        if (!line.empty() && line.size() + 1 + word.size() > perLine) lines.push_back(line), line.clear();
        line += (line.empty() ? "" : " ") + word;
        word.clear();
      }
    };
    for (char ch : subtitle) {
      if (ch == ' ')
        flush();
      else
        word += ch;
    }
    flush();
    if (!line.empty()) lines.push_back(line);
  }
  const double headH = 34 + 13.0 * double(lines.size());
  const double height = headH + kPanelH + legendH;
  std::string s = fmt::format(
      R"~(<svg xmlns="http://www.w3.org/2000/svg" width="{0:.0f}" height="{1:.0f}" viewBox="0 0 {0:.0f} {1:.0f}" font-family="sans-serif">)~"
      "\n",
      width, height);
  s += fmt::format(R"~(<rect width="100%" height="100%" fill="#fafafa"/>)~" "\n");
  s += fmt::format(R"~(<text x="12" y="22" font-size="16" font-weight="bold">{}</text>)~" "\n", xmlEscape(title));
  for (size_t i = 0; i < lines.size(); ++i)
    s += fmt::format(R"~(<text x="12" y="{:.0f}" font-size="10" fill="#555">{}</text>)~" "\n", 40 + 13.0 * double(i),
                     xmlEscape(lines[i]));
  for (size_t i = 0; i < panels.size(); ++i) s += renderPanel(panels[i], i * kPanelW, headH);
  // Legend.
  double lx = 16, ly = headH + kPanelH + 22;
  for (const char* cull : {"none", "frustum", "occlusion"}) {
    s += fmt::format(R"~(<rect x="{:.1f}" y="{:.1f}" width="12" height="12" fill="{}"/>)~" "\n", lx, ly - 10, cullColour(cull));
    s += fmt::format(R"~(<text x="{:.1f}" y="{:.1f}" font-size="12">cull {}</text>)~" "\n", lx + 16, ly, cull);
    lx += 110;
  }
  s += marker("visbuf", lx + 6, ly - 4, "#999") + "\n";
  s += fmt::format(R"~(<text x="{:.1f}" y="{:.1f}" font-size="12">visbuf</text>)~" "\n", lx + 16, ly);
  lx += 70;
  s += marker("forward", lx + 6, ly - 4, "#999") + "\n";
  s += fmt::format(R"~(<text x="{:.1f}" y="{:.1f}" font-size="12">forward</text>)~" "\n", lx + 16, ly);
  lx += 70;
  s += marker("gbuffer", lx + 6, ly - 4, "#999") + "\n";
  s += fmt::format(R"~(<text x="{:.1f}" y="{:.1f}" font-size="12">gbuffer</text>)~" "\n", lx + 16, ly);
  s += fmt::format(R"~(<text x="16" y="{:.1f}" font-size="11" fill="#333">labels: LOD threshold in px (off = full detail). Ringed points on the dashed line: the Pareto front</text>)~" "\n",
                   ly + 22);
  s += fmt::format(R"~(<text x="16" y="{:.1f}" font-size="11" fill="#333">(no other configuration is both at least as fast and at least as accurate). PSNR "exact": identical to the reference.</text>)~" "\n",
                   ly + 37);
  s += "</svg>\n";
  return s;
}

}  // namespace visbuf::tools
