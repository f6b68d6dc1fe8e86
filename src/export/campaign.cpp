#include "combabc/export/campaign.hpp"

#include <cmath>
#include <cstdio>

namespace combabc {
namespace {

std::string CampaignNumber(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

// A CSV field in double quotes, its quotes doubled (names are the user's).
std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (char ch : text) {
    if (ch == '"') out += '"';
    out += ch;
  }
  return out + '"';
}

}  // namespace

std::string CampaignDecidedBy(const CampaignView& view, std::size_t k) {
  const double run = view.run_p_fixed.at(k);
  if (!(std::abs(run - 0.5) > view.identified_margin)) return "";
  std::string out;
  for (const CampaignView::Evidence& e : view.alone) {
    const double p = e.p_fixed.at(k);
    if (std::abs(p - 0.5) > view.identified_margin && (p > 0.5) == (run > 0.5)) {
      if (!out.empty()) out += ", ";
      out += e.name;
    }
  }
  return out.empty() ? "together" : out;
}

void WriteCampaignCsv(std::ostream& out, const CampaignView& view) {
  const int n = view.clamps_per_edge;
  const double section = n > 0 ? view.length_m / n * 100 : 0.0;  // cm
  out << "clamp,name,edge,from_cm,to_cm,p_fixed_run,p_fixed_together";
  for (const CampaignView::Evidence& e : view.alone) {
    out << ',' << Quoted("p_fixed_alone:" + e.name);
  }
  out << ",decided_by\n";
  for (std::size_t k = 0; k < view.run_p_fixed.size(); ++k) {
    const int bit = static_cast<int>(k);
    const int s = n > 0 ? bit % n : bit;
    out << k + 1 << ',' << Quoted(k < view.clamp_names.size() ? view.clamp_names[k] : "") << ','
        << (bit < n ? 1 : 2) << ',' << CampaignNumber(s * section) << ','
        << CampaignNumber((s + 1) * section) << ',' << CampaignNumber(view.run_p_fixed[k]) << ','
        << CampaignNumber(view.together[k]);
    for (const CampaignView::Evidence& e : view.alone) out << ',' << CampaignNumber(e.p_fixed[k]);
    out << ',' << Quoted(CampaignDecidedBy(view, k)) << '\n';
  }
}

}  // namespace combabc
