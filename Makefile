# Install story for C and C++ users: the library (shared and static), the header and a
# pkg-config file.
#   make                     release build of libnimbus
#   make install PREFIX=...  installs into PREFIX (default /usr/local)
#   make uninstall PREFIX=...
# Then: cc app.c $(pkg-config --cflags --libs nimbus)
# PROFILE=debug installs the debug build instead (faster to build).

PREFIX ?= /usr/local
PROFILE ?= release
LIBDIR = $(DESTDIR)$(PREFIX)/lib
INCDIR = $(DESTDIR)$(PREFIX)/include
VERSION = $(shell sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n 1)
CARGO_FLAGS = $(if $(filter release,$(PROFILE)),--release,)

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
	@echo "installed nimbus $(VERSION) into $(DESTDIR)$(PREFIX)"

uninstall:
	rm -f $(INCDIR)/nimbus.h $(LIBDIR)/libnimbus.so $(LIBDIR)/libnimbus.so.$(VERSION) \
		$(LIBDIR)/libnimbus.a $(LIBDIR)/pkgconfig/nimbus.pc
