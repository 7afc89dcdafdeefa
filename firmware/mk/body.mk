# firmware/mk/body.mk: the robot's body on its Dynamixel bus (included by the Makefile). GNU make.
#
#   make busmodel     the emulated bus served on a TCP port: build/busmodel [port=7000] [bind=127.0.0.1] [run_ms=0]
#   make test-bridge  the posix robot's bridge over real UDP, tools/bridge_check.py playing the gateway
#   make test-qemu-bus the qemu board reads its servos and camera over USART1 from the standalone busmodel
#   make test-sdk     the official DynamixelSDK (dynamixel-sdk 4.1.0 from the registry, in a venv under build/)
#                     pings and reads/writes the standalone busmodel through a socat pseudo-terminal
#                     (tools/sdk_check.py); it says so and fails when python3-venv, socat or the package is missing

.PHONY: busmodel test-sdk
busmodel: $(BUILD)/busmodel
$(BUILD)/busmodel: tools/busmodel_main.c tools/busmodel.c tools/busmodel.h
	@mkdir -p $(dir $@)
	$(CC) -O2 -g $(SAN) $(FR_WARN) -Itools -o $@ tools/busmodel_main.c tools/busmodel.c

SDK_VENV := $(BUILD)/sdk-venv
$(SDK_VENV)/.ok:
	python3 -m venv $(SDK_VENV) && $(SDK_VENV)/bin/pip install -q dynamixel-sdk==4.1.0 && touch $@
test-sdk: $(BUILD)/busmodel $(SDK_VENV)/.ok
	$(SDK_VENV)/bin/python tools/sdk_check.py $(BUILD)/busmodel

# make test-bridge: the posix robot's bus bridge over real UDP with tools/bridge_check.py as the gateway (6 checks)
.PHONY: test-bridge
test-bridge: native
	python3 tools/bridge_check.py $(BUILD)/posix-w$(WINDOW)/robot

# make test-qemu-bus: the qemu board reads every servo and captures camera frames over its USART1 from the
# standalone busmodel (tools/qemu_bus_check.py)
.PHONY: test-qemu-bus
test-qemu-bus: $(BUILD)/busmodel $(BUILD)/qemu/robot.elf
	python3 tools/qemu_bus_check.py $(BUILD)/busmodel $(BUILD)/qemu/robot.elf
