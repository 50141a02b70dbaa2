// What a scan's coordinate reference system says to a reader: its name, its EPSG code and its
// linear unit, read from what the inputs carried (metadata "crs": a WKT string from a LAS WKT
// VLR or a PLY comment, and/or a LAS GeoTIFF key directory). Used by `info` and to label
// measurements and profiles in the scan's own units. No projection maths here: coordinates stay
// in the source's system (PROJ would be needed to transform them, and nothing transforms them).
//
// Facts used: OGC 01-009 (WKT 1: PROJCS, GEOGCS, COMPD_CS, UNIT, AUTHORITY) and ISO 19162 (WKT 2:
// PROJCRS, GEOGCRS, COMPOUNDCRS, LENGTHUNIT, ID); GeoTIFF 1.1 key ids (ProjectedCSTypeGeoKey 3072,
// GeographicTypeGeoKey 2048, ProjLinearUnitsGeoKey 3076, GTCitationGeoKey 1026,
// PCSCitationGeoKey 3073) and EPSG unit codes 9001 (metre), 9002 (foot), 9003 (US survey foot).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace nestlight {

struct CrsInfo {
  bool known = false;        // the inputs carried a CRS
  std::string name;          // "NAD83(HARN) / Oregon GIC Lambert (ft)"; empty when not stated
  int epsg = 0;              // the CRS's own EPSG code; 0 when not stated
  std::string unitName;      // "metre", "foot", "US survey foot", "degree"; empty when not stated
  double metresPerUnit = 0;  // 0 when not stated or angular
  bool geographic = false;   // coordinates in degrees (a GEOGCS without a projection)
  std::string source;        // "WKT", "GeoTIFF keys", "WKT and GeoTIFF keys"

  // "m", "ft", "US ft", "deg"; "units" when not stated (the scan's own, unnamed).
  std::string unitSymbol() const;
  // One line for `info`: name, EPSG code, unit and where they came from.
  std::string summary() const;
};

CrsInfo describeCrs(const nlohmann::json& crs);

}  // namespace nestlight
