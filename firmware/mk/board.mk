# firmware/mk/board.mk: the Cortex-M3 boards (included by the Makefile). GNU make.
#
#   make arm        CM-530 images (STM32F103RE, port/cm530): build/cm530/robot.{elf,hex,bin}, and
#                   build/cm530-w4/ with the stream's window at 4; they link against 512 KB / 64 KB
#   make qemu       netduino2 images (port/qemu): build/qemu/{robot,echo,measure}.elf, and build/qemu-w4/
#   make footprint  flash and static RAM of each CM-530 build, the largest stack of each entry point (stack
#                   painting) and instructions per keep-alive and per request (qemu -icount); prints a table
#                   and writes build/footprint.json
#   make test-gs1500m   the GS1500M driver's unit tests alone (also part of `make test`)
#
# The toolchain is Debian's gcc-arm-none-eabi with newlib-nano; qemu is qemu-system-arm (setup.sh installs both).

ARM_CC ?= arm-none-eabi-gcc
ARM_SIZE ?= arm-none-eabi-size
ARM_OBJCOPY ?= arm-none-eabi-objcopy
QEMU ?= qemu-system-arm
ARM_ARCH := -mcpu=cortex-m3 -mthumb
# -Os as the thesis's firmware was built for size; sections per function so the linker drops what is unused.
ARM_OPT := -Os -ffunction-sections -fdata-sections -fno-common
ARM_LDFLAGS := $(ARM_ARCH) -nostartfiles --specs=nano.specs -Wl,--gc-sections -Lld
BOARD_INCLUDES := -Iport -Iport/stm32
# Extra -D flags for the board images, e.g. BOARD_DEFS="-DBOARD_BASE_IP={10,0,0,5}" (the base station's address).
BOARD_DEFS ?=
BOARD_HEADERS := $(wildcard include/*.h port/*.h port/stm32/*.h)
STM32_SRCS := port/stm32/startup.c
# fr_port.h over the driver and the UART; the measurement program brings its own (a scripted module, its own clock).
STM32_PORT_SRCS := port/stm32/fr_port_gs1500m.c
ARM_PB_SRCS := $(FR_PB_SRCS) $(FR_GEN_SRCS)

.PHONY: arm qemu footprint test-gs1500m check-arm check-qemu


check-arm:
	@command -v $(ARM_CC) >/dev/null || { echo "$(ARM_CC) missing: run bash setup.sh" >&2; exit 1; }
check-qemu:
	@command -v $(QEMU) >/dev/null || { echo "$(QEMU) missing: run bash setup.sh" >&2; exit 1; }

# arm_variant(name, board source, extra flags, linker script): objects and images under build/<name>/.
define arm_variant
$(BUILD)/$(1)/obj/%.o: %.c $(FR_GEN_STAMP) $(BOARD_HEADERS) | check-arm
	@mkdir -p $$(dir $$@)
	$(ARM_CC) $(ARM_ARCH) $(ARM_OPT) $(FR_CFLAGS) $(BOARD_INCLUDES) $(BOARD_DEFS) $(3) -c $$< -o $$@
$(BUILD)/$(1)/pb/%.o: %.c $(FR_GEN_STAMP) | check-arm
	@mkdir -p $$(dir $$@)
	$(ARM_CC) $(ARM_ARCH) $(ARM_OPT) $(PB_CFLAGS) $(3) -c $$< -o $$@
$(1)_BASE := $(patsubst %.c,$(BUILD)/$(1)/obj/%.o,$(FR_LIB_SRCS) $(STM32_SRCS) $(2)) \
             $(patsubst %.c,$(BUILD)/$(1)/pb/%.o,$(ARM_PB_SRCS))
$(1)_PORT := $(patsubst %.c,$(BUILD)/$(1)/obj/%.o,$(STM32_PORT_SRCS))
$(1)_LD := $(4)
endef

# arm_program(variant, program, its source, port objects): one image.
define arm_program
$(BUILD)/$(1)/$(2).elf: $(BUILD)/$(1)/obj/$(3:.c=.o) $$($(1)_BASE) $(4) $$($(1)_LD) ld/sections.ld
	$(ARM_CC) $(ARM_LDFLAGS) -T $$($(1)_LD) -Wl,-Map=$(BUILD)/$(1)/$(2).map -o $$@ $$(filter %.o,$$^) -lm
$(BUILD)/$(1)/$(2).hex: $(BUILD)/$(1)/$(2).elf
	$(ARM_OBJCOPY) -O ihex $$< $$@
$(BUILD)/$(1)/$(2).bin: $(BUILD)/$(1)/$(2).elf
	$(ARM_OBJCOPY) -O binary $$< $$@
endef

$(eval $(call arm_variant,cm530,port/cm530/board_cm530.c,,ld/stm32f103re.ld))
$(eval $(call arm_variant,cm530-w4,port/cm530/board_cm530.c,-DFR_STREAM_WINDOW=4,ld/stm32f103re.ld))
$(eval $(call arm_variant,qemu,port/qemu/board_qemu.c,,ld/qemu-netduino2.ld))
$(eval $(call arm_variant,qemu-w4,port/qemu/board_qemu.c,-DFR_STREAM_WINDOW=4,ld/qemu-netduino2.ld))
$(foreach v,cm530 cm530-w4 qemu qemu-w4,$(eval $(call arm_program,$(v),robot,$(FR_EXAMPLE_SRCS),$$($(v)_PORT))))
$(foreach v,qemu qemu-w4,$(eval $(call arm_program,$(v),measure,port/qemu/measure.c,)))
$(eval $(call arm_program,qemu,echo,port/qemu/echo.c,$$(qemu_PORT)))

arm: $(BUILD)/cm530/robot.elf $(BUILD)/cm530/robot.hex $(BUILD)/cm530/robot.bin $(BUILD)/cm530-w4/robot.elf
qemu: $(BUILD)/qemu/robot.elf $(BUILD)/qemu/echo.elf $(BUILD)/qemu/measure.elf $(BUILD)/qemu-w4/robot.elf \
      $(BUILD)/qemu-w4/measure.elf

# Flash = .isr_vector + .text + .data's initial values; static RAM = .data + .bss (the reserved stack apart).
footprint: arm qemu | check-qemu
	@python3 port/qemu/footprint.py "$(QEMU)" "$(ARM_SIZE)" "$(BUILD)"

# The driver's tests alone, without nanopb (the Makefile's `make test` runs them with the library's).
test-gs1500m: $(BUILD)/tests-gs1500m/test_gs1500m
	@$<
$(BUILD)/tests-gs1500m/test_gs1500m: tests/test_gs1500m.c src/gs1500m.c include/gs1500m.h include/fr_port.h
	@mkdir -p $(dir $@)
	$(CC) -O1 -g $(FR_WARN) -Iinclude -o $@ tests/test_gs1500m.c src/gs1500m.c
