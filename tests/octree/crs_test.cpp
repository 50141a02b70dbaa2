// The CRS's name, EPSG code and unit as `info`, measurements and profiles show them, from WKT 1,
// WKT 2 and GeoTIFF keys; text that cannot be read describes an unnamed CRS, never fails.
#include "nestlight/octree/crs.h"

#include <gtest/gtest.h>

#include <fstream>

#include "test_support.h"

using namespace nestlight;

TEST(Crs, Wkt1ProjectedNamesItsUnitAndCode) {
  const CrsInfo utm = describeCrs(
      {{"wkt",
        R"w(PROJCS["WGS 84 / UTM zone 10N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563,AUTHORITY["EPSG","7030"]],AUTHORITY["EPSG","6326"]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4326"]],PROJECTION["Transverse_Mercator"],PARAMETER["central_meridian",-123],UNIT["metre",1,AUTHORITY["EPSG","9001"]],AUTHORITY["EPSG","32610"]])w"}});
  EXPECT_TRUE(utm.known);
  EXPECT_EQ(utm.name, "WGS 84 / UTM zone 10N");
  EXPECT_EQ(utm.epsg, 32610);  // the CRS's own code, not its datum's or unit's
  EXPECT_EQ(utm.unitName, "metre");
  EXPECT_EQ(utm.unitSymbol(), "m");
  EXPECT_FALSE(utm.geographic);

  const CrsInfo ft = describeCrs(
      {{"wkt",
        R"w(PROJCS["NAD83 / Ohio North (ftUS)",GEOGCS["NAD83",UNIT["degree",0.01745]],UNIT["US survey foot",0.3048006096012192]])w"}});
  EXPECT_EQ(ft.unitName, "US survey foot");
  EXPECT_EQ(ft.unitSymbol(), "US ft");
  EXPECT_NEAR(ft.metresPerUnit, 0.3048006096, 1e-9);
  EXPECT_EQ(ft.epsg, 0);
  EXPECT_NE(ft.summary().find("unit US survey foot (0.304800609601 m), from WKT"),
            std::string::npos)
      << ft.summary();
}

TEST(Crs, Wkt2CompoundAndGeographic) {
  const CrsInfo w2 = describeCrs(
      {{"wkt",
        R"w(PROJCRS["ETRS89 / UTM zone 32N",BASEGEOGCRS["ETRS89",ANGLEUNIT["degree",0.0174532925199433]],CONVERSION["UTM zone 32N",METHOD["Transverse Mercator"]],CS[Cartesian,2],AXIS["(E)",east,ORDER[1],LENGTHUNIT["metre",1]],AXIS["(N)",north,ORDER[2],LENGTHUNIT["metre",1]],ID["EPSG",25832]])w"}});
  EXPECT_EQ(w2.name, "ETRS89 / UTM zone 32N");
  EXPECT_EQ(w2.epsg, 25832);
  EXPECT_EQ(w2.unitName, "metre");

  const CrsInfo compound = describeCrs(
      {{"wkt",
        R"w(COMPD_CS["OSGB 1936 / British National Grid + ODN height",PROJCS["OSGB 1936 / British National Grid",GEOGCS["OSGB 1936",UNIT["degree",0.0174532925199433]],UNIT["metre",1],AUTHORITY["EPSG","27700"]],VERT_CS["ODN height",UNIT["metre",1]],AUTHORITY["EPSG","7405"]])w"}});
  EXPECT_EQ(compound.name, "OSGB 1936 / British National Grid + ODN height");
  EXPECT_EQ(compound.epsg, 7405);
  EXPECT_EQ(compound.unitName, "metre");

  const CrsInfo geo = describeCrs(
      {{"wkt",
        R"w(GEOGCS["WGS 84",DATUM["WGS_1984"],UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4326"]])w"}});
  EXPECT_TRUE(geo.geographic);
  EXPECT_EQ(geo.unitSymbol(), "deg");
  EXPECT_EQ(geo.epsg, 4326);
}

TEST(Crs, GeoTiffKeysAloneAndTextThatCannotBeRead) {
  // GeoKeyDirectory: version 1.1.0, 3 keys: ProjectedCSType 32610, ProjLinearUnits foot,
  // PCSCitation from the ASCII parameters.
  const CrsInfo keys =
      describeCrs({{"geotiff",
                    {{"keys", {1, 1, 0, 3, 3072, 0, 1, 32610, 3076, 0, 1, 9002, 3073, 34737, 8, 0}},
                     {"ascii", "UTM 10N|rest|"}}}});
  EXPECT_EQ(keys.epsg, 32610);
  EXPECT_EQ(keys.unitName, "foot");
  EXPECT_EQ(keys.name, "UTM 10N");
  EXPECT_EQ(keys.source, "GeoTIFF keys");

  // A key count beyond the array, a truncated WKT, garbage: unnamed, no throw.
  EXPECT_NO_THROW(describeCrs({{"geotiff", {{"keys", {1, 1, 0, 40, 3072}}}}}));
  for (const char* bad : {"PROJCS[\"x\",UNIT[\"metre\",1]", "PROJCS[\"x\",UNIT[\"metre\",oops]]",
                          "]]]", "", "PROJCS\"x\""}) {
    const CrsInfo c = describeCrs({{"wkt", bad}});
    EXPECT_TRUE(c.known);
    EXPECT_EQ(c.metresPerUnit, 0) << bad;
  }
  EXPECT_FALSE(describeCrs(nullptr).known);
  EXPECT_EQ(describeCrs(nullptr).unitSymbol(), "units");
}

TEST(Crs, AutzenIsInInternationalFeet) {
  NL_REQUIRE_SHARED("scans/autzen_trim.las");
  // The WKT VLR as the LAS reader carries it (read here from the file's bytes directly).
  std::ifstream f(nestlight::test::sharedData() / "scans/autzen_trim.las", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(f)), {});
  const size_t at = bytes.find("PROJCS[");
  ASSERT_NE(at, std::string::npos);
  const CrsInfo c = describeCrs({{"wkt", bytes.substr(at, bytes.find('\0', at) - at)}});
  EXPECT_EQ(c.name, "NAD_1983_HARN_Lambert_Conformal_Conic");
  EXPECT_EQ(c.unitName, "foot");
  EXPECT_EQ(c.metresPerUnit, 0.3048);
}
