# Install story for C and C++ users: the library (shared and static), the header and a
# pkg-config file.
#   make                     release build of libnimbus
#   make install PREFIX=...  installs into PREFIX (default /usr/local)
#   make uninstall PREFIX=...
# Then: cc app.c $(pkg-config --cflags --libs nimbus), or pkg-config --static for libnimbus.a,
# or in CMake: find_package(nimbus 0.2 CONFIG REQUIRED) + target_link_libraries(app nimbus::nimbus)
# PROFILE=debug installs the debug build instead (faster to build).

PREFIX ?= /usr/local
PROFILE ?= release
LIBDIR = $(DESTDIR)$(PREFIX)/lib
INCDIR = $(DESTDIR)$(PREFIX)/include
VERSION = $(shell sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n 1)
CARGO_FLAGS = $(if $(filter release,$(PROFILE)),--release,)

# The CMake package: find_package(nimbus CONFIG) gives nimbus::nimbus (shared) and
# nimbus::nimbus_static (static, with the system libraries it needs).
define CMAKE_CONFIG
# nimbus $(VERSION): find_package(nimbus CONFIG) gives the imported targets
#   nimbus::nimbus         the shared library libnimbus.so
#   nimbus::nimbus_static  the static library libnimbus.a (links -lm -ldl -lpthread too)
get_filename_component(_nimbus_prefix "$${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
if(NOT TARGET nimbus::nimbus)
  add_library(nimbus::nimbus SHARED IMPORTED)
  set_target_properties(nimbus::nimbus PROPERTIES
    IMPORTED_LOCATION "$${_nimbus_prefix}/lib/libnimbus.so"
    INTERFACE_INCLUDE_DIRECTORIES "$${_nimbus_prefix}/include")
  add_library(nimbus::nimbus_static STATIC IMPORTED)
  set_target_properties(nimbus::nimbus_static PROPERTIES
    IMPORTED_LOCATION "$${_nimbus_prefix}/lib/libnimbus.a"
    INTERFACE_INCLUDE_DIRECTORIES "$${_nimbus_prefix}/include"
    INTERFACE_LINK_LIBRARIES "m;dl;pthread")
endif()
unset(_nimbus_prefix)
endef
export CMAKE_CONFIG

# Version rule as for NIMBUS_ABI_VERSION: the same major, and a requested minor no newer than
# this one (before 1.0, also the same major 0 only).
define CMAKE_VERSION
set(PACKAGE_VERSION "$(VERSION)")
string(REPLACE "." ";" _nimbus_have "$${PACKAGE_VERSION}")
string(REPLACE "." ";" _nimbus_want "$${PACKAGE_FIND_VERSION}")
list(GET _nimbus_have 0 _have_major)
list(GET _nimbus_have 1 _have_minor)
list(LENGTH _nimbus_want _want_parts)
set(PACKAGE_VERSION_COMPATIBLE FALSE)
if(_want_parts EQUAL 0)
  set(PACKAGE_VERSION_COMPATIBLE TRUE)
else()
  list(GET _nimbus_want 0 _want_major)
  set(_want_minor 0)
  if(_want_parts GREATER 1)
    list(GET _nimbus_want 1 _want_minor)
  endif()
  if(_want_major EQUAL _have_major AND NOT _want_minor GREATER _have_minor)
    set(PACKAGE_VERSION_COMPATIBLE TRUE)
  endif()
endif()
if(PACKAGE_FIND_VERSION STREQUAL PACKAGE_VERSION)
  set(PACKAGE_VERSION_EXACT TRUE)
endif()
endef
export CMAKE_VERSION

.PHONY: all install uninstall
all:
	cargo build --lib $(CARGO_FLAGS)

install: all
	install -d $(LIBDIR)/pkgconfig $(INCDIR)
	install -m 644 include/nimbus.h $(INCDIR)/nimbus.h
	install -m 755 target/$(PROFILE)/libnimbus.so $(LIBDIR)/libnimbus.so.$(VERSION)
	ln -sf libnimbus.so.$(VERSION) $(LIBDIR)/libnimbus.so
	install -m 644 target/$(PROFILE)/libnimbus.a $(LIBDIR)/libnimbus.a
	printf 'prefix=%s\nlibdir=$${prefix}/lib\nincludedir=$${prefix}/include\n\nName: nimbus\nDescription: Volumetric cloud SDK (physically lit ray-marched clouds)\nVersion: %s\nLibs: -L$${libdir} -lnimbus\nLibs.private: -lm -ldl -lpthread\nCflags: -I$${includedir}\n' \
		'$(PREFIX)' '$(VERSION)' > $(LIBDIR)/pkgconfig/nimbus.pc
	install -d $(LIBDIR)/cmake/nimbus
	echo "$$CMAKE_CONFIG" > $(LIBDIR)/cmake/nimbus/nimbusConfig.cmake
	echo "$$CMAKE_VERSION" > $(LIBDIR)/cmake/nimbus/nimbusConfigVersion.cmake
	@echo "installed nimbus $(VERSION) into $(DESTDIR)$(PREFIX)"

uninstall:
	rm -f $(INCDIR)/nimbus.h $(LIBDIR)/libnimbus.so $(LIBDIR)/libnimbus.so.$(VERSION) \
		$(LIBDIR)/libnimbus.a $(LIBDIR)/pkgconfig/nimbus.pc \
		$(LIBDIR)/cmake/nimbus/nimbusConfig.cmake $(LIBDIR)/cmake/nimbus/nimbusConfigVersion.cmake
